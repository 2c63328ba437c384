#!/usr/bin/env python3
"""Writes the docs that come from the code's own tables, so none of them is typed by hand:

    docs/scene_keys.md        the whole file: `fluiddemo scene-keys` (every effect's parameter table)
    docs/replay.md            the block between `<!-- columns -->` and `<!-- end columns -->`:
                              `fluiddemo scene-keys --columns` (every effect's replay CSV columns)

    scripts/generated_docs.py FLUIDDEMO          rewrite them
    scripts/generated_docs.py FLUIDDEMO --check  exit 1, naming the file, when one is out of date
"""
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
BEGIN, END = "<!-- columns -->", "<!-- end columns -->"


def run(exe: str, *args: str) -> str:
    return subprocess.run([exe, "scene-keys", *args], check=True, capture_output=True, text=True).stdout


def main() -> int:
    if len(sys.argv) < 2 or sys.argv[1].startswith("-"):
        print(__doc__, file=sys.stderr)
        return 2
    exe, check = sys.argv[1], "--check" in sys.argv[2:]
    wanted = {ROOT / "docs/scene_keys.md": run(exe)}
    replay = ROOT / "docs/replay.md"
    text = replay.read_text(encoding="utf-8")
    if BEGIN not in text or END not in text:
        print(f"{replay.relative_to(ROOT)}: no '{BEGIN}' ... '{END}' block", file=sys.stderr)
        return 1
    head, rest = text.split(BEGIN, 1)
    wanted[replay] = head + BEGIN + "\n" + run(exe, "--columns") + END + rest.split(END, 1)[1]
    stale = [path for path, body in wanted.items() if path.read_text(encoding="utf-8") != body]
    if check:
        for path in stale:
            print(f"{path.relative_to(ROOT)} is out of date: run scripts/generated_docs.py {exe}", file=sys.stderr)
        return 1 if stale else 0
    for path in stale:
        path.write_text(wanted[path], encoding="utf-8")
        print(f"wrote {path.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
