#!/usr/bin/env python3
"""Writes the blob monster's behaviour measurements into README.md (between the blob_table markers)
from the `[blob]` lines the unit_blob tests print (tests/blob: each behaviour reaching its goal in a
scripted headless run, asserted there as a number).

    python3 scripts/blob_table.py build/dev/tests/blob/unit_blob [README.md]
"""
import re
import subprocess
import sys

BEGIN, END = "<!-- blob_table begin -->", "<!-- blob_table end -->"


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    exe = sys.argv[1]
    readme = sys.argv[2] if len(sys.argv) > 2 else "README.md"
    run = subprocess.run([exe], capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit(f"blob_table: {exe} failed (exit {run.returncode}):\n{run.stdout[-2000:]}{run.stderr[-2000:]}")
    rows = []
    for line in run.stdout.splitlines():
        m = re.match(r"\[blob\] ([^:]+): (.*)$", line)
        if m:
            rows.append((m.group(1).strip(), m.group(2).strip().replace("|", "\\|")))
    if not rows:
        sys.exit(f"blob_table: {exe} printed no [blob] lines")
    table = [BEGIN, "", f"Written by `python3 scripts/blob_table.py {exe}` (tests/blob, 1,000 particles unless named).", "",
             "| behaviour / check | measured |", "|---|---|"]
    table += [f"| {name} | {text} |" for name, text in rows]
    table += ["", END]
    text = open(readme).read()
    if BEGIN not in text or END not in text:
        sys.exit(f"blob_table: {readme} has no {BEGIN} ... {END} section")
    head, rest = text.split(BEGIN, 1)
    tail = rest.split(END, 1)[1]
    open(readme, "w").write(head + "\n".join(table) + tail)
    print(f"blob_table: {len(rows)} rows written to {readme}")


if __name__ == "__main__":
    main()
