#!/usr/bin/env python3
"""Copies measured sections of docs/*.md into README.md, so the README shows the tables the
benchmarks wrote, never hand-typed figures.

README.md marks each place with a pair of lines:

    <!-- include docs/surface.md "Figure 7 reproduction (approaches 1, 2, 3)" -->
    ... (replaced) ...
    <!-- end include -->

and gets the body of that level-2 section (up to the next "## " heading), its heading left out.

    scripts/readme_tables.py          rewrite README.md from the docs
    scripts/readme_tables.py --check  exit 1 (naming the section) when README.md is out of date
"""
import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
BEGIN = re.compile(r'^<!-- include (\S+) "([^"]+)" -->$')
END = "<!-- end include -->"


def section(doc: pathlib.Path, title: str) -> list[str]:
    lines = doc.read_text(encoding="utf-8").splitlines()
    try:
        start = lines.index("## " + title) + 1
    except ValueError:
        raise SystemExit(f"{doc.relative_to(ROOT)}: no section '## {title}'")
    end = next((k for k in range(start, len(lines)) if lines[k].startswith("## ")), len(lines))
    body = lines[start:end]
    while body and not body[0].strip():
        body.pop(0)
    while body and not body[-1].strip():
        body.pop()
    # Links and images relative to docs/ must stay valid from the repository root.
    prefix = doc.parent.relative_to(ROOT).as_posix() + "/"
    link = re.compile(r"(\]\()(?!https?:|/|#)([^)]+\))")
    return [link.sub(lambda m: m.group(1) + prefix + m.group(2), line) for line in body]


def render(readme_lines: list[str], stale: list[str]) -> list[str]:
    out, k = [], 0
    while k < len(readme_lines):
        line = readme_lines[k]
        out.append(line)
        match = BEGIN.match(line)
        k += 1
        if not match:
            continue
        try:
            end = readme_lines.index(END, k)
        except ValueError:
            raise SystemExit(f"README.md:{k}: '{line}' has no '{END}' after it")
        body = section(ROOT / match.group(1), match.group(2))
        if body != readme_lines[k:end]:
            stale.append(f'{match.group(1)} "{match.group(2)}"')
        out.extend(body)
        out.append(END)
        k = end + 1
    return out


def main() -> int:
    readme = ROOT / "README.md"
    current = readme.read_text(encoding="utf-8").splitlines()
    stale: list[str] = []
    wanted = render(current, stale)
    if "--check" in sys.argv[1:]:
        if stale:
            print("README.md is out of date with docs/ (run scripts/readme_tables.py): " + "; ".join(stale),
                  file=sys.stderr)
            return 1
        return 0
    readme.write_text("\n".join(wanted) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
