"""fluiddemo.mesh against `fluiddemo mesh`: the same bits on the test sets, errors with the CLI's
messages, and the VTK files (particles in, meshes out) read back by our own parsers."""
import struct

import numpy as np
import pytest

import fluiddemo
from conftest import DATA, read_legacy_vtk_mesh, read_ply_mesh, read_vtu_mesh, run

# (file, cube edge S) as tests/data/README.md; Rc = 3 and T = 0.2 (the defaults of both).
SETS = [("blob.xyz", 0.3), ("explosion.xyz", 0.6), ("fountain.xyz", 1.0)]


def load(name):
    return np.loadtxt(DATA / name, dtype=np.float32, ndmin=2)[:, :3]


def same_bits(a, b):
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


@pytest.mark.parametrize("name,cube", SETS)
def test_mesh_gives_the_bits_the_cli_writes(exe, tmp_path, name, cube):
    out = tmp_path / "mesh.ply"
    run(exe, "mesh", "--in", DATA / name, "--out", out, "--cube", cube, "--rc", 3, "--threshold", 0.2)
    cli = read_ply_mesh(out)
    mine = fluiddemo.mesh(load(name), radius=3.0, threshold=0.2, cube=cube)
    assert len(mine[2]) > 100
    for file_array, array in zip(cli, mine):
        assert same_bits(np.ascontiguousarray(file_array), array)


def test_mesh_does_not_depend_on_threads():
    points = load("fountain.xyz")
    one = fluiddemo.mesh(points, 3.0, 0.2, 1.0, threads=1)
    two = fluiddemo.mesh(points, 3.0, 0.2, 1.0, threads=2)
    assert all(same_bits(a, b) for a, b in zip(one, two))


def test_mesh_is_closed_and_outward():
    vertices, normals, triangles = fluiddemo.mesh(load("blob.xyz"), 3.0, 0.2, 0.3)
    # Closed: every edge is shared by exactly two triangles, in opposite directions.
    edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    forward = {tuple(e) for e in edges.tolist()}
    assert len(forward) == len(edges)
    assert all((b, a) in forward for a, b in forward)
    # Outward: the signed volume is positive and the normals are unit.
    a, b, c = (vertices[triangles[:, k]].astype(np.float64) for k in range(3))
    assert np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0 > 0.0
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-5)


def test_mesh_accepts_float64_and_lists():
    points = load("blob.xyz")
    as_float = fluiddemo.mesh(points, 3.0, 0.2, 0.3)
    as_double = fluiddemo.mesh(points.astype(np.float64), 3.0, 0.2, 0.3)
    as_list = fluiddemo.mesh(points.tolist(), 3.0, 0.2, 0.3)
    assert all(same_bits(x, y) and same_bits(x, z) for x, y, z in zip(as_float, as_double, as_list))


def test_mesh_errors_carry_the_cli_messages(exe, tmp_path):
    points = load("blob.xyz")
    with pytest.raises(ValueError, match=r"positions: expected shape \(n, 3\)"):
        fluiddemo.mesh(points[:, :2], 3.0, 0.2, 0.3)
    # A threshold the field cannot reach: the CLI's message, with the argument and source as named here.
    cli = run(exe, "mesh", "--in", DATA / "blob.xyz", "--out", tmp_path / "never.obj", "--cube", 0.3,
              "--threshold", 1e30, check=False)
    assert cli.returncode == 2
    with pytest.raises(ValueError) as raised:
        fluiddemo.mesh(points, 3.0, 1e30, 0.3)
    expected = cli.stderr.strip().removeprefix("fluiddemo mesh: ")
    expected = expected.replace("--threshold", "threshold").replace(str(DATA / "blob.xyz"), "positions")
    assert str(raised.value) == expected
    # Field and value errors come from the library, word for word the CLI's.
    bad = points.copy()
    bad[7, 1] = np.nan
    np.savetxt(tmp_path / "nan.xyz", bad)
    cli = run(exe, "mesh", "--in", tmp_path / "nan.xyz", "--out", tmp_path / "never.obj", check=False)
    assert cli.returncode != 0
    with pytest.raises(ValueError) as raised:
        fluiddemo.mesh(bad, 3.0, 0.2, 1.0)
    assert str(raised.value)
    with pytest.raises(ValueError, match="cube"):
        fluiddemo.mesh(points, 3.0, 0.2, 0.0)


def write_vtk_particles(path, points, binary):
    n = len(points)
    head = f"# vtk DataFile Version 3.0\nparticles\n{'BINARY' if binary else 'ASCII'}\nDATASET POLYDATA\nPOINTS {n} float\n"
    with open(path, "wb") as f:
        f.write(head.encode())
        if binary:
            f.write(points.astype(">f4").tobytes())
            f.write(f"\nVERTICES {n} {2 * n}\n".encode())
            f.write(np.column_stack([np.ones(n), np.arange(n)]).astype(">i4").tobytes())
        else:
            for p in points:
                f.write(("%.9g %.9g %.9g\n" % tuple(p)).encode())
            f.write(f"VERTICES {n} {2 * n}\n".encode())
            f.write("".join(f"1 {i}\n" for i in range(n)).encode())


@pytest.mark.parametrize("binary", [False, True])
def test_vtk_particles_in_mesh_like_xyz(exe, tmp_path, binary):
    points = load("blob.xyz")
    write_vtk_particles(tmp_path / "p.vtk", points, binary)
    run(exe, "mesh", "--in", tmp_path / "p.vtk", "--out", tmp_path / "vtk.ply", "--cube", 0.3)
    run(exe, "mesh", "--in", DATA / "blob.xyz", "--out", tmp_path / "xyz.ply", "--cube", 0.3)
    assert (tmp_path / "vtk.ply").read_bytes() == (tmp_path / "xyz.ply").read_bytes()


def test_vtk_particles_errors_name_the_file(exe, tmp_path):
    write_vtk_particles(tmp_path / "cut.vtk", load("blob.xyz"), True)
    data = (tmp_path / "cut.vtk").read_bytes()
    (tmp_path / "cut.vtk").write_bytes(data[:200])
    cli = run(exe, "mesh", "--in", tmp_path / "cut.vtk", "--out", tmp_path / "never.obj", check=False)
    assert cli.returncode == 1
    assert "cut.vtk:5: BINARY POINTS: 100 points need 1200 bytes" in cli.stderr
    (tmp_path / "text.vtk").write_text("# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 2 float\n0 0 0\n1 1 nan\n")
    cli = run(exe, "mesh", "--in", tmp_path / "text.vtk", "--out", tmp_path / "never.obj", check=False)
    assert cli.returncode == 1 and "text.vtk:7: 'nan' is not a finite float" in cli.stderr


@pytest.mark.parametrize("ext,reader", [(".vtk", read_legacy_vtk_mesh), (".vtu", read_vtu_mesh)])
def test_vtk_meshes_read_back_as_the_ply(exe, tmp_path, ext, reader):
    run(exe, "mesh", "--in", DATA / "blob.xyz", "--out", tmp_path / "m.ply", "--cube", 0.3)
    run(exe, "mesh", "--in", DATA / "blob.xyz", "--out", tmp_path / ("m" + ext), "--cube", 0.3)
    ply = read_ply_mesh(tmp_path / "m.ply")
    back = reader(tmp_path / ("m" + ext))
    for a, b in zip(ply, back):
        assert same_bits(np.ascontiguousarray(a), np.ascontiguousarray(b))


def test_mesher_keeps_its_scratch_and_gives_the_same_bits():
    mesher = fluiddemo.Mesher(radius=3.0, threshold=0.2, cube=0.6)
    explosion, blob = load("explosion.xyz"), load("blob.xyz")
    first = mesher.mesh(explosion)
    mesher.mesh(blob)  # another set in between: nothing of it may leak into the next mesh
    again = mesher.mesh(explosion)
    alone = fluiddemo.mesh(explosion, 3.0, 0.2, 0.6)
    assert all(same_bits(a, b) and same_bits(a, c) for a, b, c in zip(first, again, alone))


def test_read_particles_reads_what_the_cli_reads(tmp_path):
    points = load("blob.xyz")
    assert same_bits(fluiddemo.read_particles(str(DATA / "blob.xyz")), points)
    for binary in (False, True):
        write_vtk_particles(tmp_path / "p.vtk", points, binary)
        assert same_bits(fluiddemo.read_particles(str(tmp_path / "p.vtk")), points)
    with pytest.raises(ValueError, match="unknown particle file extension '.txt'"):
        fluiddemo.read_particles(str(tmp_path / "p.txt"))


@pytest.mark.parametrize("binary", [False, True])
def test_every_truncated_or_garbled_vtk_file_is_an_error_or_a_prefix(tmp_path, binary):
    points = load("blob.xyz")[:20]
    write_vtk_particles(tmp_path / "p.vtk", points, binary)
    data = (tmp_path / "p.vtk").read_bytes()
    # The particles end where the points do: after the header's 5 lines and the POINTS numbers.
    header = data.index(b"POINTS") + data[data.index(b"POINTS"):].index(b"\n") + 1
    points_end = header + 12 * len(points) if binary else data.index(b"VERTICES")
    rng = np.random.default_rng(1)
    cases = [data[:cut] for cut in range(len(data))]
    for _ in range(300):
        garbled = bytearray(data)
        for at in rng.integers(0, len(data), size=3):
            garbled[at] = int(rng.integers(0, 256))
        cases.append(bytes(garbled))
    for k, case in enumerate(cases):
        (tmp_path / "case.vtk").write_bytes(case)
        try:
            got = fluiddemo.read_particles(str(tmp_path / "case.vtk"))
        except ValueError as error:
            assert str(error).startswith(str(tmp_path / "case.vtk") + ":"), error
            continue
        # A file cut before the last point's numbers is never taken for a whole one (a text number
        # cut short is still a number: the bound is the last number's first digit).
        last = points_end if binary else data.rindex(b" ", 0, points_end) + 2
        assert k >= last, f"a file cut at {k} bytes was read"
        assert got.shape[1] == 3 and np.isfinite(got).all()


@pytest.mark.parametrize("name,binary", [("p.vtk", True), ("p.vtk", False), ("p.ply", True), ("p.xyz", True)])
def test_written_particles_read_back_bit_for_bit(tmp_path, name, binary):
    points = load("explosion.xyz") * np.float32(1.0001)  # floats with all their digits
    fluiddemo.write_particles(str(tmp_path / name), points, binary=binary)
    assert same_bits(fluiddemo.read_particles(str(tmp_path / name)), points)
    with pytest.raises(ValueError, match="exists|not overwritten"):
        fluiddemo.write_particles(str(tmp_path / name), points)
    fluiddemo.write_particles(str(tmp_path / name), points[:5], binary=binary, force=True)
    assert len(fluiddemo.read_particles(str(tmp_path / name))) == 5


def test_mesh_reads_strided_float32_rows_in_place():
    # The first three columns of a wider float32 array (row stride 16 bytes) are read in place
    # through the mesher's pointer + stride view: the same bits as a C-contiguous copy.
    points = load("blob.xyz")
    wide = np.zeros((len(points), 4), dtype=np.float32)
    wide[:, :3] = points
    strided = wide[:, :3]
    assert not strided.flags["C_CONTIGUOUS"]
    packed = fluiddemo.mesh(np.ascontiguousarray(points), 3.0, 0.2, 0.3)
    in_place = fluiddemo.mesh(strided, 3.0, 0.2, 0.3)
    assert all(same_bits(a, b) for a, b in zip(packed, in_place))
