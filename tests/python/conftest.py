"""Shared fixtures: the repository, the `fluiddemo` executable (when built) and PLY/VTK readers of
our own (no VTK module needed) for comparing files with the module's arrays."""
import os
import pathlib
import subprocess
import xml.etree.ElementTree as ElementTree

import numpy as np
import pytest

REPO = pathlib.Path(os.environ.get("FLUIDDEMO_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
DATA = REPO / "tests" / "data"


@pytest.fixture
def exe():
    path = os.environ.get("FLUIDDEMO_EXE")
    if not path:
        pytest.skip("FLUIDDEMO_EXE is not set (a build without the fluiddemo executable)")
    if not os.path.exists(path):
        pytest.fail(f"FLUIDDEMO_EXE={path} does not exist")
    return path


def run(exe, *args, check=True):
    """Runs `fluiddemo ARGS`; returns the CompletedProcess (text)."""
    done = subprocess.run([exe, *map(str, args)], capture_output=True, text=True)
    if check and done.returncode != 0:
        raise AssertionError(f"fluiddemo {' '.join(map(str, args))} exited {done.returncode}: {done.stderr}")
    return done


def read_ply_mesh(path):
    """The binary PLY `fluiddemo mesh` writes -> (vertices, normals, triangles) with the file's bits."""
    data = pathlib.Path(path).read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode().splitlines()
    assert "format binary_little_endian 1.0" in header
    v = int(next(l for l in header if l.startswith("element vertex")).split()[2])
    f = int(next(l for l in header if l.startswith("element face")).split()[2])
    vertex = np.frombuffer(data, dtype="<f4", count=6 * v, offset=end).reshape(v, 6)
    face = np.frombuffer(data, dtype=np.dtype([("n", "u1"), ("i", "<u4", 3)]), count=f, offset=end + 24 * v)
    assert (face["n"] == 3).all()
    return vertex[:, :3], vertex[:, 3:], face["i"]


def read_legacy_vtk_mesh(path):
    """A legacy BINARY POLYDATA triangle mesh with point NORMALS -> (vertices, normals, triangles)."""
    data = pathlib.Path(path).read_bytes()
    lines = data.split(b"\n", 4)
    assert lines[0].startswith(b"# vtk DataFile Version") and lines[2] == b"BINARY" and lines[3] == b"DATASET POLYDATA"
    at = len(b"\n".join(lines[:4])) + 1

    def keyword_line():
        nonlocal at
        while data[at:at + 1] == b"\n":
            at += 1
        end = data.index(b"\n", at)
        words = data[at:end].decode().split()
        at = end + 1
        return words

    words = keyword_line()
    assert words[0] == "POINTS" and words[2] == "float", words
    n = int(words[1])
    points = np.frombuffer(data, dtype=">f4", count=3 * n, offset=at).reshape(n, 3)
    at += 12 * n
    words = keyword_line()
    assert words[0] == "POLYGONS", words
    t, size = int(words[1]), int(words[2])
    assert size == 4 * t
    cells = np.frombuffer(data, dtype=">i4", count=size, offset=at).reshape(t, 4)
    at += 4 * size
    assert (cells[:, 0] == 3).all()
    assert keyword_line() == ["POINT_DATA", str(n)]
    assert keyword_line()[:2] == ["NORMALS", "Normals"]
    normals = np.frombuffer(data, dtype=">f4", count=3 * n, offset=at).reshape(n, 3)
    return points.astype(np.float32), normals.astype(np.float32), cells[:, 1:].astype(np.uint32)


def read_vtu_mesh(path):
    """A .vtu UnstructuredGrid of triangles (ASCII data arrays) -> (vertices, normals, triangles)."""
    piece = ElementTree.parse(path).getroot().find("UnstructuredGrid/Piece")
    n, t = int(piece.get("NumberOfPoints")), int(piece.get("NumberOfCells"))

    def array(parent, name=None):
        for a in piece.find(parent).findall("DataArray"):
            if name is None or a.get("Name") == name:
                assert a.get("format") == "ascii"
                return np.array(a.text.split(), dtype=np.float64)
        raise AssertionError(f"no DataArray {name} in {parent}")

    points = array("Points").astype(np.float32).reshape(n, 3)
    normals = array("PointData", "Normals").astype(np.float32).reshape(n, 3)
    connectivity = array("Cells", "connectivity").astype(np.uint32)
    offsets = array("Cells", "offsets").astype(np.int64)
    types = array("Cells", "types").astype(np.int64)
    assert (types == 5).all() and (offsets == 3 * np.arange(1, t + 1)).all()
    return points, normals, connectivity.reshape(t, 3)
