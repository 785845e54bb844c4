#!/usr/bin/env python3
"""Every link of README.md and docs/*.md to a page of the docs, or to a
heading of one (PAGE.md#anchor, #anchor), lands: the page exists and has a
heading whose anchor (GitHub's: lower case, punctuation dropped, spaces to
hyphens) is the one linked. Prints each link that does not; exits 1 if
there is one.

    python3 scripts/doc_links.py [ROOT]
"""
import pathlib
import re
import sys

LINK = re.compile(r'\]\(([\w./-]*\.md)?(?:#([\w-]+))?\)')


def anchor(heading):
    h = heading.strip().lower()
    h = re.sub(r'[^\w\- ]', '', h)
    return h.replace(' ', '-')


def main() -> int:
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parent.parent)
    pages = [root / 'README.md'] + sorted((root / 'docs').glob('*.md'))
    anchors = {}
    for p in pages:
        block = False
        found = set()
        for line in p.read_text(encoding='utf-8').splitlines():
            if line.startswith('```'):
                block = not block
            elif not block and line.startswith('#'):
                found.add(anchor(line.lstrip('#')))
        anchors[p.resolve()] = found
    bad = 0
    for p in pages:
        for n, line in enumerate(p.read_text(encoding='utf-8').splitlines(), 1):
            for m in LINK.finditer(line):
                target, frag = m.group(1), m.group(2)
                if not target and not frag:
                    continue
                page = (p.parent / target).resolve() if target else p.resolve()
                if page not in anchors:
                    if target and not (p.parent / target).exists():
                        print(f'{p.relative_to(root)}:{n}: {m.group(0)[2:-1]}: no such page')
                        bad += 1
                    continue
                if frag and frag not in anchors[page]:
                    print(f'{p.relative_to(root)}:{n}: {m.group(0)[2:-1]}: no heading with that anchor')
                    bad += 1
    print(f'{bad} links that do not land' if bad else 'every link lands')
    return 1 if bad else 0


if __name__ == '__main__':
    sys.exit(main())
