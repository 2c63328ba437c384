#!/usr/bin/env python3
"""What any change to the slice splat's field sums alone can win against the dense peer (issue 34).

Issue 34 asks the mesher for at most 0.8x the dense splat + Flying Edges peer's time on every set. The
automatic route (the dense scan) sums every set's field by slice splat, one function, `splatSlice`;
everything else (block plan, the sort, the scan's classification, vertices and triangles) does not
depend on how the field is summed. Ours without the splat's instructions is therefore a floor for any
change to the field sums, reached only by a splat that costs nothing. The table prints that floor
against the peer, with the automatic block plan and with one block (`ours-one-block`: no second
block, which the plan takes for two threads' sake).

A second table splits the peer the same way (its splat, Flying Edges with and without normals,
`peer-no-normals`) on all four sets: any route that splats a dense value lattice as the peer does and
then runs Flying Edges costs at least the peer without its normals, which says what such a route
must save over VTK's Flying Edges to reach 0.8 of the peer.

Each figure is one warm mesh on one thread counted by callgrind between client requests
(`bench_surface_peers --count SET ROUTE`), split by `callgrind_annotate --inclusive=yes`.

Usage, from the repository root after a Release build with VTK 9 (bench_surface_peers):
  python3 tests/bench/surface_field_floor.py [--bench build/test/tests/bench/bench_surface_peers]
"""
import argparse
import re
import subprocess
import tempfile

PEER_SETS = ["fountain", "blob", "explosion", "spray"]
SETS = PEER_SETS
TOTAL = re.compile(r"^([0-9,]+) \(100\.0+%\)\s+PROGRAM TOTALS", re.M)
SPLAT = re.compile(r"^\s*([0-9,]+) \([ 0-9.]+%\)\s+.*BlockMesher<[^>]*>::splatSlice<(true|false)>")
PEER_SPLAT = re.compile(r"^\s*([0-9,]+) \([ 0-9.]+%\)\s+.*DensePeer::splatAvx2\(")
FLYING_EDGES = re.compile(r"^\s*([0-9,]+) \([ 0-9.]+%\)\s+.*vtkFlyingEdges3D::RequestData\(")


def profile(bench, set_name, route, work):
    """callgrind_annotate's inclusive listing of one --count run."""
    out = f"{work}/{set_name}.{route}.callgrind"
    subprocess.run(["valgrind", "--tool=callgrind", "--instr-atstart=no", f"--callgrind-out-file={out}", bench,
                    "--count", set_name, route], check=True, capture_output=True)
    return subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", out], check=True,
                          capture_output=True, text=True).stdout


def program_total(text):
    return int(TOTAL.search(text).group(1).replace(",", ""))


def first(pattern, text, what):
    for line in text.splitlines():
        if m := pattern.match(line):
            return int(m.group(1).replace(",", ""))
    raise SystemExit(f"no {what} in the profile")


def count(bench, set_name, route, work):
    text = profile(bench, set_name, route, work)
    total = program_total(text)
    # The function itself, not the lambdas inside it (their lines name it too, and its inclusive count has them).
    splat = sum(int(m.group(1).replace(",", "")) for line in text.splitlines()
                if "{lambda" not in line and (m := SPLAT.match(line)))
    return total, splat


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bench", default="build/test/tests/bench/bench_surface_peers")
    args = ap.parse_args()
    print("| set | blocks | ours Ir | of it, the slice splat | ours without the splat | peer Ir "
          "| ours / peer | floor: without the splat / peer |")
    print("|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as work:
        for set_name in SETS:
            peer, _ = count(args.bench, set_name, "peer", work)
            for route, label in (("ours", "automatic plan"), ("ours-one-block", "one block")):
                total, splat = count(args.bench, set_name, route, work)
                if splat == 0:
                    raise SystemExit(f"{set_name} {route}: no splatSlice in the profile (not the slice-splat route?)")
                print(f"| {set_name} | {label} | {total:,} | {splat:,} | {total - splat:,} | {peer:,} "
                      f"| {total / peer:.2f} | {(total - splat) / peer:.2f} |")
        print()
        print("| set | peer Ir | of it, the splat | Flying Edges with normals | Flying Edges without normals "
              "| peer without normals | without normals / peer | 0.8 peer | 0.8 peer - the splat - the rest |")
        print("|---|---|---|---|---|---|---|---|---|")
        for set_name in PEER_SETS:
            with_normals = profile(args.bench, set_name, "peer", work)
            without = profile(args.bench, set_name, "peer-no-normals", work)
            total = program_total(with_normals)
            total_without = program_total(without)
            splat = first(PEER_SPLAT, with_normals, "DensePeer::splatAvx2")
            fe = first(FLYING_EDGES, with_normals, "vtkFlyingEdges3D::RequestData")
            fe_without = first(FLYING_EDGES, without, "vtkFlyingEdges3D::RequestData")
            rest = total - splat - fe  # zeroing the lattice, bounds, the z sort, VTK's pipeline outside RequestData
            print(f"| {set_name} | {total:,} | {splat:,} | {fe:,} | {fe_without:,} | {total_without:,} "
                  f"| {total_without / total:.2f} | {0.8 * total:,.0f} | {0.8 * total - splat - rest:,.0f} |")


if __name__ == "__main__":
    main()
