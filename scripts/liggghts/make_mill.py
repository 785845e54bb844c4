#!/usr/bin/env python3
"""Writes the LIGGGHTS version of millcharge's benchmark mill.

The mill is that of assets/cases/bench_100k.toml cut to 0.5 m (the length
LIGGGHTS was timed on in issue 5): D 1.0 m, 16 lifter rows, first at 0 rad,
profile height 0.03 m, top width 0.03 m, face angle 20 deg, 19-21 mm steel
balls, 75 % of critical speed, Hertz with tangential history and rolling
friction, dt 5 us. Writes into --out:

  mill_shell.stl   ASCII STL of the shell and the 16 lifter bars (full
                   length): the mill's inside outline extruded along z
  mill_plates.stl  ASCII STL of the two end plates (discs of radius D/2)
  mill.data        LIGGGHTS data file: the balls, packed as millcharge packs
                   them (dropped one by one onto the lowest of a grid of
                   columns, src/core/mill_case.cpp build_scene), mill at rest
  params.in        LIGGGHTS variables (materials, dt, skin, rotation period,
                   ...) that in.mill_common, in.mill_warmup, in.mill_timed read

Geometry, as millcharge builds it (src/core/lifters.cpp lifter_polygon): a
bar centred at angle a is the trapezoid, in (u radial, t tangential) local
coordinates, (r_top, -w/2), (r_base, -b), (r_base, b), (r_top, w/2) with
r_top = R - h, r_base = R + h/4 (behind the shell), b = w/2 + (r_base -
r_top) tan(face). Only the part inside the shell can be touched, so the STL
cuts each side face where it meets the shell circle; the shell between the
bars is the circle in chords of at most --chord m. Axis +z from z = 0 to L,
gravity -y, the mill turns counter-clockwise about +z (DESIGN.md).

The mesh is kept lean, as a LIGGGHTS user would (each triangle costs LIGGGHTS
time every step the mesh moves): by default the shell and lifter faces are
single triangles over the whole length, chords 0.02 m (0.1 mm from the
circle), end plates of 0.1 m triangles: 704 triangles. A mesh of 9,596
(--chord 0.01 --shell-pieces 10 --plate-chord 0.03) made LIGGGHTS' steps
about 2.5 times as slow on a packed charge.

Standard library only.
"""
import argparse
import heapq
import math
import os
import random
import sys


def lifter_polygon(R, height, top_width, face_deg, angle):
    """millcharge's lifter_polygon (src/core/lifters.cpp), counter-clockwise."""
    tan_face = math.tan(math.radians(face_deg))
    r_top = R - height
    r_base = R + 0.25 * height
    half_top = 0.5 * top_width
    half_base = half_top + (r_base - r_top) * tan_face
    c, s = math.cos(angle), math.sin(angle)

    def at(u, t):
        return (u * c - t * s, u * s + t * c)

    return [at(r_top, -half_top), at(r_base, -half_base), at(r_base, half_base), at(r_top, half_top)]


def side_meets_shell(R, height, top_width, face_deg, angle, sign):
    """Where the side face (sign -1: the -t face, +1: the +t face) meets the
    shell circle of radius R, in x-y."""
    tan_face = math.tan(math.radians(face_deg))
    r_top = R - height
    half_top = 0.5 * top_width
    # t(u) = sign*(half_top + (u - r_top) tan); solve u^2 + t^2 = R^2 for u.
    a0 = half_top - r_top * tan_face  # t = sign*(a0 + u tan)
    A = 1.0 + tan_face * tan_face
    B = 2.0 * a0 * tan_face
    C = a0 * a0 - R * R
    u = (-B + math.sqrt(B * B - 4 * A * C)) / (2 * A)
    t = sign * (a0 + u * tan_face)
    c, s = math.cos(angle), math.sin(angle)
    return (u * c - t * s, u * s + t * c)


def polygon_signed_distance(poly, x, y):
    inside = True
    best = 1e300
    n = len(poly)
    for k in range(n):
        ax, ay = poly[k]
        bx, by = poly[(k + 1) % n]
        ex, ey = bx - ax, by - ay
        if (x - ax) * ey - (y - ay) * ex > 0:
            inside = False
        t = ((x - ax) * ex + (y - ay) * ey) / (ex * ex + ey * ey)
        t = min(1.0, max(0.0, t))
        best = min(best, math.hypot(x - (ax + t * ex), y - (ay + t * ey)))
    return -best if inside else best


def cross_section(R, rows, first, height, top_width, face_deg, chord):
    """The mill's inside outline in x-y, counter-clockwise: for each bar the
    point where its trailing (-t) face meets the shell, its two top corners,
    the point where its leading (+t) face meets the shell, then the shell arc
    to the next bar."""
    pts = []
    for k in range(rows):
        a = first + 2 * math.pi * k / rows
        poly = lifter_polygon(R, height, top_width, face_deg, a)
        p_in = side_meets_shell(R, height, top_width, face_deg, a, -1)
        p_out = side_meets_shell(R, height, top_width, face_deg, a, +1)
        pts += [p_in, poly[0], poly[3], p_out]
        a_next = first + 2 * math.pi * (k + 1) / rows
        q = side_meets_shell(R, height, top_width, face_deg, a_next, -1)
        th0 = math.atan2(p_out[1], p_out[0])
        th1 = math.atan2(q[1], q[0])
        while th1 <= th0:
            th1 += 2 * math.pi
        n = max(1, int(math.ceil((th1 - th0) * R / chord)))
        for i in range(1, n):
            th = th0 + (th1 - th0) * i / n
            pts.append((R * math.cos(th), R * math.sin(th)))
    return pts


def end_plate(R, chord):
    """Triangles (in x-y, counter-clockwise) covering the disc of radius R:
    rings of points, about as far apart along a ring as the rings are apart,
    halving the count inwards, and a fan at the centre. The disc runs under
    the lifter ends (balls cannot reach there), so it needs no cut-outs."""
    n = max(16, 8 * int(math.ceil(2 * math.pi * R / chord / 8)))
    rings = []
    r = R
    while r > 0.5 * chord:
        phase = 0.5 * (len(rings) % 2)  # stagger the rings
        rings.append([(r * math.cos(2 * math.pi * (i + phase) / n), r * math.sin(2 * math.pi * (i + phase) / n))
                      for i in range(n)])
        r -= chord
        while n > 8 and 2 * math.pi * r / n < 0.7 * chord:
            n //= 2
    tris = []
    for outer, inner in zip(rings, rings[1:]):
        no, ni = len(outer), len(inner)
        # both rings are regular: zip them in angle order
        i = j = 0
        while i < no or j < ni:
            o0, o1 = outer[i % no], outer[(i + 1) % no]
            n0, n1 = inner[j % ni], inner[(j + 1) % ni]
            ao = math.atan2(o1[1], o1[0]) % (2 * math.pi) + (2 * math.pi if i + 1 >= no else 0)
            an = math.atan2(n1[1], n1[0]) % (2 * math.pi) + (2 * math.pi if j + 1 >= ni else 0)
            if j >= ni or (i < no and ao <= an):
                tris.append((o0, o1, n0))
                i += 1
            else:
                tris.append((o0, n1, n0))
                j += 1
    last = rings[-1]
    for k in range(len(last)):
        tris.append((last[k], last[(k + 1) % len(last)], (0.0, 0.0)))
    return tris


def facet_normal(a, b, c):
    ux, uy, uz = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    vx, vy, vz = c[0] - a[0], c[1] - a[1], c[2] - a[2]
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    m = math.sqrt(nx * nx + ny * ny + nz * nz) or 1.0
    return nx / m, ny / m, nz / m


def write_stl(path, name, facets):
    with open(path, "w") as f:
        f.write("solid %s\n" % name)
        for a, b, c in facets:
            f.write("  facet normal %.9e %.9e %.9e\n    outer loop\n" % facet_normal(a, b, c))
            for v in (a, b, c):
                f.write("      vertex %.12e %.12e %.12e\n" % v)
            f.write("    endloop\n  endfacet\n")
        f.write("endsolid %s\n" % name)
    return len(facets)


def shell_facets(outline, length, pieces):
    """The shell and lifter faces: the outline extruded over z in [0, length]
    in `pieces` along z, normals towards the axis."""
    facets = []
    nz = max(1, pieces)
    zs = [length * i / nz for i in range(nz + 1)]
    n = len(outline)
    for k in range(n):
        (x0, y0), (x1, y1) = outline[k], outline[(k + 1) % n]
        for z0, z1 in zip(zs, zs[1:]):
            a, b, c, d = (x0, y0, z0), (x1, y1, z0), (x1, y1, z1), (x0, y0, z1)
            facets.append((a, d, c))  # the outline is counter-clockwise:
            facets.append((a, c, b))  # this order faces the axis
    return facets


def plate_facets(R, length, chord):
    """The end plates z = 0 (normal +z) and z = length (normal -z)."""
    facets = []
    for p, q, r in end_plate(R, chord):
        facets.append(((p[0], p[1], 0.0), (q[0], q[1], 0.0), (r[0], r[1], 0.0)))
        facets.append(((p[0], p[1], length), (r[0], r[1], length), (q[0], q[1], length)))
    return facets


def pack(R, length, lifters, n_balls, dmin, dmax, seed):
    """millcharge's initial packing (src/core/mill_case.cpp build_scene),
    with Python's random instead of std::mt19937_64: each ball, sizes
    shuffled, is dropped onto the lowest of a grid of columns (pitch just over
    the smallest diameter), lifted over the balls already placed, clear of the
    shell, the lifters and the end plates."""
    rng = random.Random(seed)
    radii = [0.5 * (dmin + (dmax - dmin) * rng.random()) for _ in range(n_balls)]
    rng.shuffle(radii)
    rmin, rmax = 0.5 * dmin, 0.5 * dmax
    gap = 0.02 * rmin
    pitch = 2 * rmin + 2 * gap
    nx = int(math.floor((2 * R - 2 * gap) / pitch))
    nzc = max(1, int(math.floor((length - 2 * gap) / pitch)))
    z0 = 0.5 * (length - (nzc - 1) * pitch)
    cols = []
    for ix in range(nx):
        x = -0.5 * (nx - 1) * pitch + ix * pitch
        if abs(x) + rmin + gap >= R:
            continue
        for iz in range(nzc):
            cols.append([x, z0 + iz * pitch, -R])
    heap = [(c[2], k) for k, c in enumerate(cols)]
    heapq.heapify(heap)
    closed = [False] * len(cols)
    cell = 2 * rmax + 2 * gap
    grid = {}
    bounds = []
    for poly in lifters:
        cx = sum(p[0] for p in poly) / len(poly)
        cy = sum(p[1] for p in poly) / len(poly)
        bounds.append((cx, cy, max(math.hypot(p[0] - cx, p[1] - cy) for p in poly)))

    def clear_of_lifters(x, y, r):
        for k, (cx, cy, br) in enumerate(bounds):
            if math.hypot(x - cx, y - cy) > br + r + gap:
                continue
            if polygon_signed_distance(lifters[k], x, y) < r + gap:
                return False
        return True

    balls = []

    def rest_height(x, y, z, r):
        moved = True
        while moved:
            moved = False
            ix, iy, iz = int((x + R) // cell), int((y + R) // cell), int(z // cell)
            for cz in (iz - 1, iz, iz + 1):
                for cy in (iy - 1, iy, iy + 1):
                    for cx in (ix - 1, ix, ix + 1):
                        for j in grid.get((cx, cy, cz), ()):
                            bx, by, bz, br = balls[j]
                            reach = r + br + gap
                            dx, dy, dz = x - bx, y - by, z - bz
                            if dx * dx + dy * dy + dz * dz >= reach * reach:
                                continue
                            h2 = reach * reach - dx * dx - dz * dz
                            y = by + math.sqrt(max(0.0, h2)) + 1e-9 * R
                            moved = True
        return y

    for r in radii:
        placed = False
        while heap and not placed:
            top, k = heapq.heappop(heap)
            if closed[k] or top != cols[k][2]:
                continue
            cxz = cols[k]
            ring = R - r - gap
            x = cxz[0] + 0.1 * pitch * (2 * rng.random() - 1)
            z = min(max(cxz[1] + 0.1 * pitch * (2 * rng.random() - 1), r + gap), length - r - gap)
            if abs(x) >= ring:
                closed[k] = True
                continue
            ceil_y = math.sqrt(ring * ring - x * x)
            y = max(-ceil_y, top + r + gap)
            while True:
                y = rest_height(x, y, z, r)
                if y > ceil_y or clear_of_lifters(x, y, r):
                    break
                y += 0.25 * r
            if y > ceil_y:
                closed[k] = True
                continue
            key = (int((x + R) // cell), int((y + R) // cell), int(z // cell))
            grid.setdefault(key, []).append(len(balls))
            balls.append((x, y, z, r))
            cols[k][2] = y + r
            heapq.heappush(heap, (cols[k][2], k))
            placed = True
        if not placed:
            sys.exit("make_mill.py: only %d of %d balls fit in the mill; lower --balls" % (len(balls), n_balls))
    return balls


def hertz_damping_for_restitution(e):
    """millcharge's damping d (gamma = d*sqrt(S*m*), src/core/restitution.cpp):
    the dimensionless Hertz contact x'' = -x^1.5 - d*sqrt(3/2)*x^0.25*x', with
    the force clipped at zero, rebounds at e."""
    def rebound(d, h=1e-4):
        x, v = 0.0, 1.0
        s15 = math.sqrt(1.5)

        def acc(x, v):
            xp = x if x > 0 else 0.0
            return -xp * math.sqrt(xp) - d * s15 * math.sqrt(math.sqrt(xp)) * v

        for _ in range(2000000):
            k1x, k1v = v, acc(x, v)
            k2x, k2v = v + 0.5 * h * k1v, acc(x + 0.5 * h * k1x, v + 0.5 * h * k1v)
            k3x, k3v = v + 0.5 * h * k2v, acc(x + 0.5 * h * k2x, v + 0.5 * h * k2v)
            k4x, k4v = v + h * k3v, acc(x + h * k3x, v + h * k3v)
            x += h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x)
            v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
            if x <= 0 or (v < 0 and acc(x, v) >= 0):
                return -v
        return 0.0

    if e >= 1:
        return 0.0
    lo, hi = 0.0, 1.0
    while rebound(hi) > e:
        hi *= 2
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        if rebound(mid) > e:
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-7 * hi:
            break
    return 0.5 * (lo + hi)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--diameter", type=float, default=1.0, help="mill diameter inside the liner, m")
    p.add_argument("--length", type=float, default=0.5, help="mill length, m")
    p.add_argument("--rows", type=int, default=16)
    p.add_argument("--first-angle", type=float, default=0.0, help="angle of the first row, deg")
    p.add_argument("--lifter-height", type=float, default=0.03)
    p.add_argument("--lifter-top-width", type=float, default=0.03)
    p.add_argument("--lifter-face-angle", type=float, default=20.0, help="deg")
    p.add_argument("--balls", type=int, default=16412, help="number of balls (millcharge check's count)")
    p.add_argument("--dmin", type=float, default=0.019, help="smallest ball diameter, m")
    p.add_argument("--dmax", type=float, default=0.021, help="largest ball diameter, m (= dmin: one size)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--speed-fraction", type=float, default=0.75)
    p.add_argument("--dt", type=float, default=5e-6)
    p.add_argument("--density", type=float, default=7800.0)
    p.add_argument("--youngs", type=float, default=2e11)
    p.add_argument("--poisson", type=float, default=0.3)
    p.add_argument("--restitution", type=float, default=0.4)
    p.add_argument("--friction", type=float, default=0.4)
    p.add_argument("--rolling-friction", type=float, default=0.01)
    p.add_argument("--damping", choices=("millcharge", "liggghts"), default="millcharge",
                   help="millcharge: give LIGGGHTS the restitution whose beta gives millcharge's "
                        "calibrated damping (same gamma_n, gamma_t); liggghts: give it --restitution as is")
    p.add_argument("--chord", type=float, default=0.02, help="longest shell chord of the STL, m (0.02: 0.1 mm from the circle)")
    p.add_argument("--shell-pieces", type=int, default=1,
                   help="pieces of the shell and lifter faces along z (1: triangles the mill's length)")
    p.add_argument("--plate-chord", type=float, default=0.1, help="edge length of the end plates' triangles, m")
    a = p.parse_args()

    R = 0.5 * a.diameter
    first = math.radians(a.first_angle)
    os.makedirs(a.out, exist_ok=True)
    lifters = [lifter_polygon(R, a.lifter_height, a.lifter_top_width, a.lifter_face_angle,
                              first + 2 * math.pi * k / a.rows) for k in range(a.rows)]
    outline = cross_section(R, a.rows, first, a.lifter_height, a.lifter_top_width, a.lifter_face_angle, a.chord)
    n_facets = write_stl(os.path.join(a.out, "mill_shell.stl"), "shell", shell_facets(outline, a.length, a.shell_pieces))
    n_facets += write_stl(os.path.join(a.out, "mill_plates.stl"), "plates", plate_facets(R, a.length, a.plate_chord))

    balls = pack(R, a.length, lifters, a.balls, a.dmin, a.dmax, a.seed)
    r_min = min(b[3] for b in balls)
    margin = 0.02 * R + a.lifter_height
    with open(os.path.join(a.out, "mill.data"), "w") as f:
        f.write("millcharge benchmark mill, %d balls (make_mill.py)\n\n" % len(balls))
        f.write("%d atoms\n1 atom types\n\n" % len(balls))
        f.write("%.6f %.6f xlo xhi\n%.6f %.6f ylo yhi\n%.6f %.6f zlo zhi\n\n"
                % (-R - margin, R + margin, -R - margin, R + margin, -margin, a.length + margin))
        f.write("Atoms\n\n")
        for i, (x, y, z, r) in enumerate(balls):
            f.write("%d 1 %.9e %.6f %.9e %.9e %.9e\n" % (i + 1, 2 * r, a.density, x, y, z))

    # Speed and damping exactly as millcharge derives them.
    critical_rpm = 42.3 / math.sqrt(a.diameter - a.dmax)  # src/core/mill_case.cpp
    omega = a.speed_fraction * critical_rpm * 2 * math.pi / 60
    skin = 0.2 * r_min  # src/sim/solver.cpp default_skin
    d = hertz_damping_for_restitution(a.restitution)
    beta = -d / (2 * math.sqrt(5.0 / 6.0))  # LIGGGHTS: gamma = -2 sqrt(5/6) beta sqrt(S m*)
    e_matched = math.exp(beta * math.pi / math.sqrt(1 - beta * beta))
    e_input = e_matched if a.damping == "millcharge" else a.restitution
    mass = sum(a.density * 4.0 / 3.0 * math.pi * b[3] ** 3 for b in balls)
    with open(os.path.join(a.out, "params.in"), "w") as f:
        f.write("# written by scripts/liggghts/make_mill.py\n")
        for k, v in [
            ("n_balls", len(balls)), ("length", a.length), ("radius", R),
            ("dt", a.dt), ("skin", skin), ("omega", omega), ("period", 2 * math.pi / omega),
            ("youngs", a.youngs), ("poisson", a.poisson), ("restitution", e_input),
            ("friction", a.friction), ("rolling_friction", a.rolling_friction),
            ("rest_speed", 0.01 * math.sqrt(9.81 * a.diameter)),
            ("max_settle_steps", int(round((2.0 + 4.0 * math.sqrt(a.diameter / 9.81)) / a.dt))),
        ]:
            f.write("variable %-18s equal %.12g\n" % (k, v))
    print("make_mill.py: %s: %d facets, %d balls %.1f-%.1f mm (%.1f kg), skin %.4g m, omega %.6g rad/s "
          "(%.4g rpm), restitution for LIGGGHTS %.4f (%s damping: millcharge d %.4f)"
          % (a.out, n_facets, len(balls), 2000 * r_min, 2000 * max(b[3] for b in balls), mass, skin, omega,
             omega * 60 / (2 * math.pi), e_input, a.damping, d))
    print("make_mill.py: lifter row 0 (x, y) m: " + ", ".join("(%.6f, %.6f)" % v for v in lifters[0]))


if __name__ == "__main__":
    main()
