"""`fluiddemo mesh --in 'frames/frame_{}.xyz' --out 'meshes/frame_{}.obj'`: every frame meshed, a
progress line, existing outputs skipped unless --force (a stopped run resumes), a failing frame
named while the others are finished."""
import re

import numpy as np

from conftest import DATA, run


def make_frames(folder, count):
    folder.mkdir()
    blob = np.loadtxt(DATA / "blob.xyz", dtype=np.float32)
    for k in range(count):
        np.savetxt(folder / f"frame_{k:04d}.xyz", blob + np.float32(0.01 * k), fmt="%.6f")


def mesh_sequence(exe, tmp_path, *extra):
    return run(exe, "mesh", "--in", tmp_path / "frames" / "frame_{}.xyz", "--out", tmp_path / "meshes" / "frame_{}.obj",
               "--cube", 0.3, *extra, check=False)


def test_a_hundred_frames_mesh_show_progress_and_resume(exe, tmp_path):
    make_frames(tmp_path / "frames", 100)
    first = mesh_sequence(exe, tmp_path)
    assert first.returncode == 0, first.stderr
    meshes = sorted((tmp_path / "meshes").iterdir())
    assert [m.name for m in meshes] == [f"frame_{k:04d}.obj" for k in range(100)]
    assert re.search(r"mesh: 100/100 frames, [0-9.]+ frames/s, 0 s left", first.stderr), first.stderr
    assert "meshed 100 frames" in first.stdout
    # Each frame is the mesh of its own file: the same bits as meshing that file alone.
    run(exe, "mesh", "--in", tmp_path / "frames" / "frame_0042.xyz", "--out", tmp_path / "alone.obj", "--cube", 0.3)
    assert (tmp_path / "alone.obj").read_bytes() == (tmp_path / "meshes" / "frame_0042.obj").read_bytes()

    # Stopped part way: the frames meshed stay, the rest are done on the next run.
    for k in (3, 50, 99):
        (tmp_path / "meshes" / f"frame_{k:04d}.obj").unlink()
    marker = tmp_path / "meshes" / "frame_0010.obj"
    marker.write_text("mine\n")
    resumed = mesh_sequence(exe, tmp_path)
    assert resumed.returncode == 0, resumed.stderr
    assert "100 frames" in resumed.stderr and "97 already meshed (skipped" in resumed.stderr
    assert "meshed 3 frames" in resumed.stdout
    assert marker.read_text() == "mine\n"  # not overwritten without --force
    forced = mesh_sequence(exe, tmp_path, "--force")
    assert forced.returncode == 0 and "meshed 100 frames" in forced.stdout
    assert marker.read_text() != "mine\n"


def test_a_failing_frame_is_named_and_the_others_finish(exe, tmp_path):
    make_frames(tmp_path / "frames", 6)
    (tmp_path / "frames" / "frame_0002.xyz").write_text("0 0 0\n1 2 garbage\n")
    done = mesh_sequence(exe, tmp_path, "--frame-jobs", 2)
    assert done.returncode == 1
    assert "frame 0002 failed:" in done.stderr and "frame_0002.xyz:2:" in done.stderr
    assert "1 of 6 frames failed" in done.stderr
    written = sorted(m.name for m in (tmp_path / "meshes").iterdir())
    assert written == [f"frame_{k:04d}.obj" for k in (0, 1, 3, 4, 5)]


def test_frame_jobs_do_not_change_the_meshes(exe, tmp_path):
    make_frames(tmp_path / "frames", 4)
    one = mesh_sequence(exe, tmp_path, "--frame-jobs", 1, "--threads", 2)
    assert one.returncode == 0
    first = {m.name: m.read_bytes() for m in (tmp_path / "meshes").iterdir()}
    two = mesh_sequence(exe, tmp_path, "--frame-jobs", 2, "--threads", 2, "--force")
    assert two.returncode == 0
    assert first == {m.name: m.read_bytes() for m in (tmp_path / "meshes").iterdir()}


def test_pattern_usage_errors(exe, tmp_path):
    make_frames(tmp_path / "frames", 2)
    mixed = run(exe, "mesh", "--in", tmp_path / "frames" / "frame_{}.xyz", "--out", tmp_path / "one.obj", check=False)
    assert mixed.returncode == 2 and "both sequence patterns" in mixed.stderr
    none = run(exe, "mesh", "--in", tmp_path / "frames" / "other_{}.xyz", "--out", tmp_path / "m_{}.obj", check=False)
    assert none.returncode == 2 and "no file matches" in none.stderr
