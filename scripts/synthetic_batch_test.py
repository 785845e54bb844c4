#!/usr/bin/env python3
"""A synthetic batch grinding test for `millcharge grind --fit`, made from a
known ore's batch products (docs/grinding-fit.md).

Reads the grind.csv that `millcharge grind RUN --ore ORE --time T1,T2,...`
wrote, picks SIEVES class tops from the feed's top down, adds uniform
scatter of +-NOISE percentage points to every passing below the top sieve
(the same scatter for the same --seed), and prints a batch test file. With
--correlation RHO the scatter of each product moves together from one sieve
to the next (e_k = RHO e_(k-1) + sqrt(1 - RHO^2) u_k, coarse to fine, u
uniform in +-1, so that each reading keeps the variance of +-NOISE uniform
scatter), as a sieve analysis whose sieves pass their errors on.
It is a stand-in for a laboratory test, and says so in its title.

  python3 scripts/synthetic_batch_test.py RUN/grind/grind.csv --sieves 12 --noise 1 --holdup-kg 1.134 > test.toml
"""
import argparse
import csv
import sys


def xorshift(seed):
    """Uniform numbers in [-1, 1], the same on every machine."""
    state = seed & 0xFFFFFFFFFFFFFFFF
    while True:
        state ^= (state << 13) & 0xFFFFFFFFFFFFFFFF
        state ^= state >> 7
        state ^= (state << 17) & 0xFFFFFFFFFFFFFFFF
        yield 2.0 * (state >> 11) / 9007199254740992.0 - 1.0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("grind_csv")
    ap.add_argument("--sieves", type=int, default=12, help="sieves below the top one (default 12)")
    ap.add_argument("--skip", type=int, default=1, help="class tops skipped below the top sieve (default 1)")
    ap.add_argument("--noise", type=float, default=0.0, help="uniform scatter, +- percentage points (default 0)")
    ap.add_argument("--correlation", type=float, default=0.0,
                    help="the scatter's correlation from one sieve to the next, 0 to 0.98 (default 0)")
    ap.add_argument("--seed", type=int, default=88172645463325252)
    ap.add_argument("--title", default="")
    ap.add_argument("--holdup-kg", type=float, default=0.0, help="the ore in the test mill (kg); 0: left out")
    a = ap.parse_args()
    with open(a.grind_csv, newline="") as f:
        rows = list(csv.reader(f))
    head, body = rows[0], rows[1:]
    times = []
    for col, name in enumerate(head[2:], start=2):
        if name.endswith(" lower 95") or name.endswith(" upper 95"):
            continue  # a fitted ore's 95 % interval beside its product
        if not name.startswith("batch ") or not name.endswith(" min"):
            sys.exit(f"{a.grind_csv}: column {name!r} is not a batch product; grind with --time only")
        times.append((float(name[6:-4]), col))
    picked = [body[0]] + body[a.skip:a.skip + a.sieves]
    if len(picked) < a.sieves + 1:
        sys.exit(f"{a.grind_csv}: only {len(body)} class tops; ask for fewer --sieves")
    if not 0 <= a.correlation <= 0.98:
        sys.exit(f"--correlation {a.correlation:g}: must lie in 0 .. 0.98")
    noise = xorshift(a.seed)
    rho = a.correlation
    carried = [0.0]

    def scatter(p, k):
        if k == 0 or a.noise == 0:
            return float(p)
        u = next(noise)
        carried[0] = u if k == 1 or rho == 0 else rho * carried[0] + (1 - rho * rho) ** 0.5 * u
        return min(1.0, max(0.0, float(p) + a.noise / 100 * carried[0]))

    title = a.title or (f"synthetic test from {a.grind_csv}, +-{a.noise:g} pp uniform scatter" +
                        (f", correlated {rho:g} from sieve to sieve" if rho else ""))
    print("# A synthetic batch grinding test, made by scripts/synthetic_batch_test.py from the")
    print("# products of a known ore: not a laboratory measurement.")
    print(f'title = "{title}"')
    print(f"noise_pp = {max(a.noise, 0.1):g}")
    if a.holdup_kg > 0:
        print(f"holdup_kg = {a.holdup_kg:g}")
    print("sieve_mm = [" + ", ".join(f"{float(r[0]) / 1000:.10g}" for r in picked) + "]")
    print("\n[feed]\npassing = [" + ", ".join(f"{float(r[1]):.10f}" for r in picked) + "]")
    for t, col in times:
        vals = [scatter(r[col], k) for k, r in enumerate(picked)]
        print(f"\n[[product]]\ntime_min = {t:g}\npassing = [" + ", ".join(f"{v:.10f}" for v in vals) + "]")


if __name__ == "__main__":
    main()
