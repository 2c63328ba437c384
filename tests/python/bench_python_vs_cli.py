"""Cost of meshing from Python against the CLI on the same particle sets (docs/use-the-libraries.md).
   PYTHONPATH=BUILD/python /usr/bin/python3 tests/python/bench_python_vs_cli.py BUILD/game/fluiddemo [--runs N]
Per set, median ms per mesh of: the CLI as a process (start, read the .xyz, mesh, weld, write .ply);
the CLI's warm extraction alone (--reps); fluiddemo.mesh (a new extractor per call, welded numpy
arrays out); fluiddemo.Mesher.mesh (extractor kept). Runs are interleaved so load drifts hit all."""
import argparse
import os
import pathlib
import statistics
import subprocess
import tempfile
import time

import numpy as np

import fluiddemo

DATA = pathlib.Path(__file__).resolve().parents[2] / "tests" / "data"
SETS = [("blob.xyz", 0.3), ("explosion.xyz", 0.6), ("fountain.xyz", 1.0), ("spray.xyz", 1.0)]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("exe")
    parser.add_argument("--runs", type=int, default=15)
    parser.add_argument("--threads", type=int, default=0)
    args = parser.parse_args()
    out = pathlib.Path(tempfile.mkdtemp()) / "m.ply"
    print(f"threads {args.threads or os.cpu_count()}, {args.runs} runs each, median ms per mesh")
    print("| set | particles | triangles | CLI process | CLI extract (warm) | fluiddemo.mesh | Mesher.mesh (warm) |")
    print("|---|---|---|---|---|---|---|")
    for name, cube in SETS:
        points = np.loadtxt(DATA / name, dtype=np.float32)
        mesher = fluiddemo.Mesher(3.0, 0.2, cube, threads=args.threads)
        mesher.mesh(points)
        cli, call, warm = [], [], []
        cmd = [args.exe, "mesh", "--in", str(DATA / name), "--out", str(out), "--cube", str(cube), "--force",
               "--threads", str(args.threads)]
        for _ in range(args.runs):
            t = time.perf_counter()
            subprocess.run(cmd, check=True, capture_output=True)
            cli.append(time.perf_counter() - t)
            t = time.perf_counter()
            _, _, triangles = fluiddemo.mesh(points, 3.0, 0.2, cube, threads=args.threads)
            call.append(time.perf_counter() - t)
            t = time.perf_counter()
            mesher.mesh(points)
            warm.append(time.perf_counter() - t)
        reps = subprocess.run(cmd + ["--reps", str(args.runs)], check=True, capture_output=True, text=True).stdout
        extract = float(reps.split("median")[1].split()[0])
        ms = lambda xs: f"{1e3 * statistics.median(xs):.2f}"
        print(f"| {name} | {len(points)} | {len(triangles)} | {ms(cli)} | {extract:.2f} | {ms(call)} | {ms(warm)} |")


if __name__ == "__main__":
    main()
