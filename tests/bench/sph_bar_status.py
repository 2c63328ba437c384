#!/usr/bin/env python3
"""Reads the dambreak_box and game-fountain tables that bench_sph / bench_game_fountain printed and
writes issue 4's performance bar as a markdown table: the best two-thread row of ours that
qualifies on error, against the SPlisHSPlasH reference figures quoted in issue 4.

    sph_bar_status.py BOX_TABLE.md FOUNTAIN_TABLE.md
"""
import sys

# SPlisHSPlasH on this machine, 2 threads, from issue 4's text (s compute per simulated s, mean
# density error in %).
SPLISHSPLASH = {"DFSPH": (13.6, 0.045), "WCSPH": (79.0, 0.33)}
FRAME_MS = 1000.0 / 60.0


def rows(path):
    out = []
    for line in open(path, encoding="utf-8"):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) < 2 or cells[0].startswith("---") or cells[0].startswith("solver") or cells[0].startswith(
                "configuration"):
            continue
        out.append(cells)
    return out


def percent(cell):
    return float(cell.replace("%", "").strip())


def main(box_path, fountain_path):
    print("| bar (issue 4, two threads) | required | best row of ours that qualifies on error | ours | status |")
    print("|---|---|---|---|---|")
    box = rows(box_path)
    for solver, (seconds, error) in SPLISHSPLASH.items():
        limit = seconds / 2.0
        # columns: label, ms/step, mean dt, iterations, mean error, p99 error, max error, s/s wall, CPU s/s
        mine = [r for r in box if r[0].startswith(solver) and r[0].endswith("(2)") and percent(r[4]) <= error]
        if not mine:
            print(f"| {solver}: 2x faster than SPlisHSPlasH at <= its error | <= {limit:.1f} s per simulated s at "
                  f"<= {error} % | none at <= {error} % | - | **not met** |")
            continue
        best = min(mine, key=lambda r: float(r[7]))
        met = float(best[7]) <= limit
        print(f"| {solver}: 2x faster than SPlisHSPlasH at <= its error | <= {limit:.1f} s per simulated s at "
              f"<= {error} % | {best[0]} | {best[7]} s at {best[4]} | {'met' if met else '**not met**'} |")
    fountain = rows(fountain_path)
    # columns: label, particles, ms/frame median, worst, steps/frame, iterations/step, mean error, p99 error, max error
    mine = [r for r in fountain if r[0].endswith("(2)") and percent(r[6]) <= 1.0]
    limit = FRAME_MS / 2.0
    if mine:
        best = min(mine, key=lambda r: float(r[2]))
        met = float(best[2]) <= limit
        print(f"| game aim: 10k-particle fountain at 60 Hz in half a frame | <= {limit:.2f} ms per 1/60 s frame at "
              f"<= 1 % | {best[0]}, {best[1]} particles | {best[2]} ms at {best[6]} | "
              f"{'met' if met else '**not met**'} |")
    else:
        print(f"| game aim: 10k-particle fountain at 60 Hz in half a frame | <= {limit:.2f} ms per 1/60 s frame at "
              f"<= 1 % | none at <= 1 % | - | **not met** |")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: sph_bar_status.py BOX_TABLE.md FOUNTAIN_TABLE.md")
    main(sys.argv[1], sys.argv[2])
