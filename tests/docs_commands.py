#!/usr/bin/env python3
"""Runs the commands of the docs' code blocks, shortened, as a user would
after the README's two commands: every line of README.md and docs/*.md in
a code block that begins with `build/millcharge`, `bash scripts/run.sh`,
`python3 scripts/` or `sed `, in page order, each page in a scratch folder
of its own that holds `assets`, `scripts` and `build` of the checkout.

Shortened: a run turns 0.2 s after a 0.02 s settle (a study one stage of
that, a comparison of studies without hours beyond theirs), a bench times 20 steps, a window draws 3 frames under xvfb-run, a
sweep prints its jobs instead of submitting them. A case of more than
30,000 balls is checked (`check` with the same case and keys) instead of
run. A command whose input the page does not make (a placeholder such as
DATE-TIME, a file the reader writes from a block of TOML) is listed as
skipped, with the reason. Any other command that exits non-zero fails
the test, with its page and line.
"""
import argparse
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile

PREFIXES = ('build/millcharge ', 'build/millcharge\n', 'bash scripts/run.sh', 'python3 scripts/', 'sed ', '$ ',
            'xvfb-run ', 'for ', 'MILLCHARGE_DEVICE=', 'python3 -m json.tool')

# The skips a page is expected to have (page, a piece of the command): a
# new skip fails the test, so that a broken command cannot hide as one.
EXPECTED_SKIPS = [
    ('docs/sweeps.md', 'lifters.toml'),               # the reader writes it from the page's TOML
    ('docs/sweeps.md', '/scratch/$USER'),             # a cluster's scratch
    ('docs/sweeps.md', 'lab2x2.toml'),                # written from the page's TOML
    ('docs/sweeps.md', '/tmp/demo/lab2x2'),
    ('docs/sweeps.md', 'collect runs/lab_speed'),     # the sweep before it is printed, not run
    ('docs/viewer.md', 'view-lab-DATE-TIME'),         # the folder a window's save names by its time
    ('docs/viewer.md', 'view --from runs/lab3 '),     # the page's first list, before the run that makes it
    ('docs/viewer.md', 'runs/lab3-h40'),              # made by a window's edit and save
    ('docs/viewer.md', 'runs/lab3w'),
    ('docs/viewer.md', 'runs/lab35'),
    ('docs/gpu.md', '--device gpu'),                  # a GPU this machine may lack
    ('docs/gpu.md', 'rusticl'),                       # another OpenCL driver, tested by its own label
    ('docs/gpu.md', 'RUSTICL_ENABLE'),
    ('docs/grinding.md', 'sweeps/lifters'),           # a sweep of the lifters the page only names
    ('docs/grinding.md', 'grind runs/lab_bc --ore assets/ores/example_t10'),  # runs grinding-scale-up.md makes
    ('docs/grinding.md', 'grind runs/bond --ore assets/ores/example_t10'),
    ('docs/grinding-scale-up.md', 'runs/mill_d_bc'),  # seed mill D's slice: over an hour
    ('docs/grinding-intervals.md', 'seq 101 140'),    # a bootstrap of 40 refits: minutes
    ('docs/grinding-intervals.md', 'seq 1 30'),       # 30 draws of two tests, fitted: minutes
    ('docs/liner-life.md', 'runs/lab-life/stage-08'), # an eight-stage study, shortened to one stage here
    ('docs/liner-life-mesh.md', 'runs/lab-mesh-life'),  # a mesh worn by a 0.2 s run's start-up turns over
                                                         # (tests/test_life_mesh.cpp runs a coarser one)
    ('docs/liner-life-mesh.md', 'runs/lab-mesh-compare'),  # compares that study
    ('docs/liner-life-mesh.md', 'runs/lab-twin-life'),  # the bars' twin, worn as that mesh is
    ('docs/liner-life-mesh.md', 'runs/sag-whole-life'),  # the whole SAG stand-in: an hour on 2 cores
    ('docs/reliability.md', '--resume runs/lab1'),    # after Ctrl-C
    ('docs/commands.md', '--resume runs/b'),          # after Ctrl-C, a crash or a time limit
]
MAX_BALLS = 30000
SHORT_RUN = ['--duration', '0.2', '--set', 'run.warmup=0.05', '--set', 'run.settle=0.02']


def commands_of(path):
    """(line number, command, what the page shows it print) for each command
    line of the page's code blocks; a transcript's ($ command) output is the
    lines after it up to the next prompt or the block's end."""
    out, block, pending, start, prompt = [], False, '', 0, False
    shown = None  # the output lines of the last transcript command
    for k, line in enumerate(open(path, encoding='utf-8'), 1):
        if line.startswith('```'):
            block = not block
            pending = ''
            shown = None
            continue
        if not block:
            continue
        text = line.rstrip('\n')
        if shown is not None and not pending and not text.strip().startswith('$ '):
            shown.append(text)
            continue
        if pending:
            pending += ' ' + text.strip()
        elif text.strip().startswith(PREFIXES):
            first = text.strip()
            prompt = first.startswith('$ ')
            if prompt:  # a transcript: the command after the prompt
                first = first[2:]
                if 'millcharge' not in first:
                    continue
            if first.startswith(('xvfb-run ', 'for ', 'MILLCHARGE_DEVICE=')) and 'build/millcharge' not in first:
                continue
            pending, start = first, k
        else:
            continue
        if pending.endswith('\\'):
            pending = pending[:-1].rstrip()
            continue
        shown = [] if prompt else None
        out.append((start, pending, shown))
        pending = ''
    return out


def split(command):
    """Arguments and the redirection (`> file`) of a command, comments dropped."""
    lex = shlex.shlex(command, posix=True, punctuation_chars='>|&;')
    lex.whitespace_split = True
    lex.commenters = '#'
    words = list(lex)
    tail = []
    for mark in ('>', '|', '&&', ';'):
        if mark in words:
            at = words.index(mark)
            words, tail = words[:at], words[at:]
            break
    return words, tail


def option(args, name):
    return args[args.index(name) + 1] if name in args and args.index(name) + 1 < len(args) else None


def drop(args, name, has_value=True):
    while name in args:
        at = args.index(name)
        del args[at:at + (2 if has_value else 1)]
    return args


class Runner:
    def __init__(self, root, binary, keep):
        self.root, self.binary, self.keep = root, binary, keep
        self.results = []
        self.xvfb = shutil.which('xvfb-run')

    def balls(self, cwd, case_args):
        """Balls of a case with its keys, by `check` (None: check failed)."""
        p = subprocess.run([self.binary, 'check'] + case_args, cwd=cwd, capture_output=True, text=True)
        m = re.search(r'([\d,]+) balls', p.stdout + p.stderr)
        return int(m.group(1).replace(',', '')) if m else None

    def case_args(self, args):
        """The case and its --set keys of a run/life/view/bench command."""
        out, k = [], 0
        while k < len(args):
            a = args[k]
            if a == '--set':
                out += args[k:k + 2]
                k += 2
                continue
            if a.startswith('--'):
                k += 2 if a in ('--out', '--duration', '--device', '--precision', '--stages', '--hours',
                                '--until-height', '--calibrate-loss', '--calibrate-hours', '--calibrate-rate',
                                '--steps', '--warmup', '--from', '--tile', '--books', '--frames', '--screenshot',
                                '--edit', '--resume', '--liner', '--save-state') else 1
                continue
            out.append(a)
            k += 1
        return out

    def shorten(self, cwd, words):
        """The command to run, 'check' args instead, or a reason to skip."""
        text = ' '.join(words)
        if words[0] == 'for':
            return None, 'a shell loop over folders the page names'
        if words[0].startswith(('MILLCHARGE_DEVICE=', 'RUSTICL_ENABLE=')):
            return None, f'{words[0]}: another OpenCL driver (its own ctest label)'
        if words[0] == 'xvfb-run':  # the page's own window: run it as the view rule below does
            at = words.index('build/millcharge') if 'build/millcharge' in words else -1
            if at < 0:
                return words, None
            words = words[at:]
            drop(words, '--frames')
            drop(words, '--screenshot')
            drop(words, '--steps-per-frame')
        for placeholder in ('DATE-TIME', '$USER', '/scratch/'):
            if placeholder in text:
                return None, f'placeholder {placeholder}'
        if words[0] == 'bash' and words[1] == 'scripts/run.sh':
            words = [self.binary, 'run'] + words[2:]
        if words[0] != 'build/millcharge' and words[0] != self.binary:
            return None, None  # another program (sed, python3): as the page writes it
        args = words[1:]
        sub = args[0] if args else ''
        rest = args[1:]
        device = option(rest, '--device')
        if device and device not in ('auto', 'cpu', 'pocl') and not re.match(r'\d+:\d+$', device):
            return None, f'--device {device}: a GPU this machine may lack'
        if sub == 'run':
            out = option(rest, '--out')
            if out and os.path.exists(os.path.join(cwd, out, 'summary.json')) and '--resume' not in rest:
                return None, f'{out} is made above on this page'
            if '--resume' in rest:
                folder = option(rest, '--resume')
                if not os.path.isdir(os.path.join(cwd, folder)):
                    return None, f'{folder} is not made on this page'
                if '--duration' not in rest and os.path.exists(os.path.join(cwd, folder, 'summary.json')):
                    return None, f'a resume after Ctrl-C: the shortened run in {folder} finished'
                if '--duration' in rest:
                    drop(rest, '--duration')
                    rest += ['--duration', '0.3']
                return [self.binary, 'run'] + rest, None
            drop(rest, '--duration')
            n = self.balls(cwd, self.case_args(rest))
            if n is not None and n > MAX_BALLS:
                return [self.binary, 'check'] + self.case_args(rest), None
            return [self.binary, 'run'] + rest + SHORT_RUN + ['--quiet'], None
        if sub == 'life':
            if any(a.startswith('walls.mesh') for a in rest) or '--axial-segments' in rest:
                return None, 'a mesh liner wears by what a full run books (a short run\'s start-up turns it over)'
            # One stage of the page's length: its hours over its stages.
            stages, hours = option(rest, '--stages'), option(rest, '--hours')
            if stages and hours:
                at = rest.index('--hours')
                rest[at + 1] = repr(float(hours) / int(stages))
            drop(rest, '--stages')
            drop(rest, '--duration')
            n = self.balls(cwd, self.case_args(rest))
            if n is not None and n > MAX_BALLS:
                return [self.binary, 'check'] + self.case_args(rest), None
            return [self.binary, 'life'] + rest + ['--stages', '1'] + SHORT_RUN + ['--quiet'], None
        if sub == 'life-compare':
            # The page's studies are one stage each here: hours of theirs
            # (--at, --measured) may lie beyond them.
            drop(rest, '--at')
            drop(rest, '--measured')
            valued = {'--label', '--out', '--profile', '--at', '--measured'}
            studies = [a for k, a in enumerate(rest) if not a.startswith('--') and (k == 0 or rest[k - 1] not in valued)]
            missing = [a for a in studies if not os.path.isdir(os.path.join(cwd, a))]
            if missing:
                return None, f'{missing[0]} is a study this page does not make here'
            return [self.binary, 'life-compare'] + rest + ['--quiet'], None
        if sub == 'bench':
            drop(rest, '--steps')
            if '--tile' in rest:
                at = rest.index('--tile')
                rest[at + 1] = '2'
            if '--from' not in rest:
                drop(rest, '--warmup')
                rest += ['--warmup', '0.01']
                n = self.balls(cwd, self.case_args(rest))
                if n is not None and n > MAX_BALLS:
                    return [self.binary, 'check'] + self.case_args(rest), None
            return [self.binary, 'bench'] + rest + ['--steps', '20', '--books', 'on', '--quiet'], None
        if sub == 'view':
            if not self.xvfb:
                return None, 'no xvfb-run'
            if '--from' in rest and not os.path.isdir(os.path.join(cwd, option(rest, '--from'))):
                return None, f'{option(rest, "--from")} is not made on this page'
            # Enough frames for the page's edits (--edit FRAME:KEY=VALUE).
            frames = 3
            for k, a in enumerate(rest):
                if a == '--edit' and k + 1 < len(rest) and ':' in rest[k + 1]:
                    frames = max(frames, int(rest[k + 1].split(':')[0]) + 2)
            return ['xvfb-run', '-a', self.binary, 'view'] + rest + ['--frames', str(frames), '--screenshot',
                                                                     'view.png'], None
        if sub == 'sweep':
            if rest and rest[0] == 'run':
                for flag in ('--slurm', '--local'):
                    if flag in rest:
                        at = rest.index(flag)
                        has_n = flag == '--local' and at + 1 < len(rest) and rest[at + 1].isdigit()
                        del rest[at:at + (2 if has_n else 1)]
                rest.append('--print')
            if rest and rest[0] == 'collect' and not os.path.isdir(os.path.join(cwd, rest[1])):
                return None, f'{rest[1]} is not made on this page'
            if rest and rest[0] in ('check', 'run') and not os.path.exists(os.path.join(cwd, rest[1])):
                return None, f'{rest[1]}: the reader writes it from the page'
            return [self.binary, 'sweep'] + rest, None
        if sub == 'grind':
            for f in [rest[0]] + [option(rest, o) for o in ('--ore', '--fit', '--scale-from') if option(rest, o)]:
                if not os.path.exists(os.path.join(cwd, f)):
                    return None, f'{f} is not made on this page'
            return [self.binary, 'grind'] + rest, None
        return [self.binary] + args, None

    def page(self, md):
        cmds = commands_of(md)
        if not cmds:
            return
        name = os.path.relpath(md, self.root)
        cwd = tempfile.mkdtemp(prefix='docs_' + os.path.basename(md).replace('.md', '') + '_')
        for d in ('assets', 'scripts', 'build'):
            os.symlink(os.path.join(self.root, d), os.path.join(cwd, d))
        try:
            for line, command, shown in cmds:
                words, tail = split(command)
                if not words:
                    continue
                if command.split('#')[0].strip() == 'bash scripts/run.sh':
                    # The README's first command (set-up, build, the lab
                    # mill): its run, shortened, where the page's globs find it.
                    words = ['bash', 'scripts/run.sh', '--out', 'runs/lab-docs']
                argv, why = self.shorten(cwd, words)
                if argv is None and why is None:  # run as written
                    argv, tail = None, []
                    shell = command
                elif argv is None and why.endswith('is made above on this page'):
                    # The page repeats a command it gave above: done then.
                    self.results.append((name, line, command, 'skipped', why))
                    continue
                if argv is None and why is not None:
                    expected = any(page == name and piece in command for page, piece in EXPECTED_SKIPS)
                    self.results.append((name, line, command, 'skipped' if expected else 'FAILED',
                                         why if expected else f'skipped unexpectedly: {why}'))
                    if not expected:
                        print(f'FAILED  {name}:{line}: {command}\n        skipped unexpectedly: {why}', flush=True)
                    continue
                # (A glob stays for the shell to expand.)
                if argv is not None:
                    shell = ' '.join(a if re.fullmatch(r'[\w./*-]*\*[\w./*-]*', a) else shlex.quote(a) for a in argv) + (
                        ' ' + ' '.join(tail) if tail else '')
                # (A pipe into head ends its writer early: no pipefail there.)
                pipefail = ['-o', 'pipefail'] if '| head' not in command else []
                p = subprocess.run(['bash'] + pipefail + ['-c', shell], cwd=cwd, capture_output=True, text=True,
                                   timeout=900)
                status = 'ok' if p.returncode == 0 else 'FAILED'
                detail = '' if p.returncode == 0 else f'exit {p.returncode}: ' + (p.stderr or p.stdout).strip()[-600:]
                # A transcript that shows the command refusing its input: the
                # refusal it shows, word for word, with exit status 2.
                first = next((x.strip() for x in (shown or []) if x.strip()), '')
                if p.returncode != 0 and first.startswith('millcharge: '):
                    if p.returncode == 2 and first in p.stderr:
                        status, detail = 'ok', '(the refusal the page shows)'
                    else:
                        detail += f'\n        the page shows: {first}'
                self.results.append((name, line, command, status, (shell if shell != command else '') + detail))
                print(f'{status:7s} {name}:{line}: {command}' + (f'\n        ran: {shell}' if shell != command else '')
                      + (f'\n        {detail}' if detail else ''), flush=True)
        finally:
            if not self.keep:
                shutil.rmtree(cwd, ignore_errors=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--root', required=True)
    ap.add_argument('--binary', required=True)
    ap.add_argument('--only', help='one page (its file name)')
    ap.add_argument('--keep', action='store_true')
    o = ap.parse_args()
    r = Runner(os.path.abspath(o.root), os.path.abspath(o.binary), o.keep)
    pages = [os.path.join(o.root, 'README.md')] + sorted(
        os.path.join(o.root, 'docs', f) for f in os.listdir(os.path.join(o.root, 'docs')) if f.endswith('.md'))
    for md in pages:
        if o.only and os.path.basename(md) != o.only:
            continue
        r.page(md)
    ran = [x for x in r.results if x[3] != 'skipped']
    failed = [x for x in r.results if x[3] == 'FAILED']
    for x in r.results:
        if x[3] == 'skipped':
            print(f'skipped {x[0]}:{x[1]}: {x[2]} ({x[4]})')
    print(f'docs commands: {len(r.results)} found, {len(ran)} run, {len(failed)} failed, '
          f'{len(r.results) - len(ran)} skipped')
    return 1 if failed else 0


if __name__ == '__main__':
    sys.exit(main())
