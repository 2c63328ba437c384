#!/usr/bin/env python3
"""The pure pieces of scripts/appearance_doc.py (docs/appearance.md's command): the PLY reader,
welding, components / holes / volume of made-up closed meshes, mask labelling, the continuum iso
radius and the projected sphere radius. Plain unittest (runs without pytest); exits 77 (ctest's
skip) when numpy is missing."""
import math
import pathlib
import sys
import tempfile
import unittest

try:
    import numpy as np
except ImportError:  # pragma: no cover
    print("numpy missing: skipped")
    sys.exit(77)

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "scripts"))
import appearance_doc as ad  # noqa: E402


def cube_mesh(size=1.0):
    """A unit cube, 8 shared vertices, 12 outward triangles."""
    v = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], dtype=float) * size
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    t = []
    for a, b, c, d in quads:
        t += [(a, b, c), (a, c, d)]
    return v, np.array(t)


def torus_mesh(big=2.0, small=0.5, n=48, m=24):
    """A torus of n × m quads (two triangles each), shared vertices, outward."""
    u = np.arange(n) * 2 * np.pi / n
    w = np.arange(m) * 2 * np.pi / m
    uu, ww = np.meshgrid(u, w, indexing="ij")
    v = np.stack([(big + small * np.cos(ww)) * np.cos(uu), small * np.sin(ww),
                  (big + small * np.cos(ww)) * np.sin(uu)], -1).reshape(-1, 3)
    idx = lambda i, j: (i % n) * m + (j % m)  # noqa: E731
    t = []
    for i in range(n):
        for j in range(m):
            a, b, c, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
            t += [(a, c, b), (a, d, c)]
    return v, np.array(t)


class MeshPieces(unittest.TestCase):
    def test_cube_volume_components_holes(self):
        v, t = cube_mesh()
        self.assertAlmostEqual(ad.mesh_volume(v, t), 1.0, places=12)
        topo = ad.mesh_topology(v, t)
        self.assertEqual(topo["components"], 1)
        self.assertEqual(topo["holes"], 0)
        self.assertEqual(topo["boundary_edges"], 0)
        self.assertEqual(topo["nonmanifold_edges"], 0)

    def test_torus_has_one_hole(self):
        v, t = torus_mesh()
        topo = ad.mesh_topology(v, t)
        self.assertEqual((topo["components"], topo["holes"], topo["boundary_edges"]), (1, 1, 0))
        exact = 2 * math.pi ** 2 * 2.0 * 0.5 ** 2
        self.assertGreater(ad.mesh_volume(v, t), 0.97 * exact)  # inscribed polygons: a little less
        self.assertLess(ad.mesh_volume(v, t), exact)

    def test_two_cubes_and_a_torus_are_three_components(self):
        v1, t1 = cube_mesh()
        v2, t2 = cube_mesh()
        v2 = v2 + 5.0
        v3, t3 = torus_mesh()
        v3 = v3 + np.array([20.0, 0.0, 0.0])
        v = np.concatenate([v1, v2, v3])
        t = np.concatenate([t1, t2 + len(v1), t3 + len(v1) + len(v2)])
        topo = ad.mesh_topology(v, t)
        self.assertEqual((topo["components"], topo["holes"]), (3, 1))
        self.assertEqual(sorted(topo["genus"]), [0, 0, 1])
        self.assertAlmostEqual(ad.mesh_volume(v[: len(v1) + len(v2)], t[: len(t1) + len(t2)]), 2.0, places=12)

    def test_open_cube_counts_boundary_edges_not_holes(self):
        v, t = cube_mesh()
        topo = ad.mesh_topology(v, t[2:])  # one face (two triangles) removed
        self.assertEqual(topo["boundary_edges"], 4)
        self.assertEqual(topo["open_components"], 1)
        self.assertEqual(topo["holes"], 0)

    def test_weld_merges_unshared_vertices(self):
        v, t = cube_mesh()
        soup = v[t.reshape(-1)] + 1e-7  # every triangle with its own three vertices
        soup_t = np.arange(len(soup)).reshape(-1, 3)
        self.assertEqual(ad.mesh_topology(soup, soup_t)["components"], 12)
        wv, wt = ad.weld(soup, soup_t, 1e-4)
        self.assertEqual(len(wv), 8)
        topo = ad.mesh_topology(wv, wt)
        self.assertEqual((topo["components"], topo["holes"], topo["boundary_edges"]), (1, 0, 0))
        self.assertAlmostEqual(ad.mesh_volume(wv, wt), 1.0, places=5)

    def test_ply_round_trip(self):
        v, t = torus_mesh(n=8, m=6)
        n = ad.vertex_normals(v, t)
        with tempfile.TemporaryDirectory() as d:
            path = pathlib.Path(d) / "torus.ply"
            ad.write_ply(path, v, t, n)
            rv, rn, rt = ad.read_ply(path)
            np.testing.assert_allclose(rv, v.astype(np.float32), rtol=0, atol=0)
            np.testing.assert_allclose(rn, n.astype(np.float32), rtol=0, atol=0)
            np.testing.assert_array_equal(rt, t)
            ad.write_ply(path, v, t)
            self.assertIsNone(ad.read_ply(path)[1])

    def test_normals_rms(self):
        self.assertAlmostEqual(ad.rms_angle_from_vertical_deg([[0, 1, 0], [0, 2, 0]]), 0.0)
        tilt = math.radians(10)
        n = [[math.sin(tilt), math.cos(tilt), 0], [0, math.cos(tilt), -math.sin(tilt)]]
        self.assertAlmostEqual(ad.rms_angle_from_vertical_deg(n), 10.0, places=6)
        # a torus's area-weighted vertex normals point away from its tube's centre line
        v, t = torus_mesh()
        n = ad.vertex_normals(v, t)
        ring = v.copy()
        ring[:, 1] = 0.0
        ring *= (2.0 / np.linalg.norm(ring, axis=1))[:, None]
        out = (v - ring) / 0.5
        self.assertGreater(np.einsum("ij,ij->i", n, out).min(), 0.99)


class SurfacePieces(unittest.TestCase):
    def test_surface_csv_and_pool_top(self):
        pool = np.array([[0.0, 0.0, 0.0], [10.0, 3.0, 10.0]])
        rows = [
            (0, 0, 5.0, 3.4, 5.0, 0.0, 1.0, 0.0),                # top, middle: counted, 0 deg
            (1, 0, 5.0, 3.4, 6.0, math.sin(0.3), math.cos(0.3), 0.0),  # top, middle: counted
            (2, 0, 1.0, 3.4, 5.0, 1.0, 0.0, 0.0),                # within the margin of x = 0
            (3, 0, 5.0, 1.0, 5.0, 1.0, 0.0, 0.0),                # the lower half (a side)
        ]
        with tempfile.TemporaryDirectory() as d:
            path = pathlib.Path(d) / "surface.csv"
            path.write_text("x,y,px,py,pz,nx,ny,nz\n" + "".join(",".join(str(v) for v in r) + "\n" for r in rows))
            points, normals = ad.read_surface_csv(path)
            self.assertEqual(points.shape, (4, 3))
            rms, count = ad.pool_top_normal_rms(points, normals, pool, margin=3.0)
            self.assertEqual(count, 2)
            self.assertAlmostEqual(rms, math.degrees(0.3) / math.sqrt(2.0), places=4)
            path.write_text("x,y,px,py,pz,nx,ny,nz\n")
            points, normals = ad.read_surface_csv(path)
            self.assertEqual(len(points), 0)
            self.assertEqual(ad.pool_top_normal_rms(points, normals, pool, 3.0)[1], 0)


class ImagePieces(unittest.TestCase):
    def test_ring_is_one_component_with_one_hole(self):
        y, x = np.mgrid[0:40, 0:40]
        r = np.hypot(x - 20, y - 20)
        self.assertEqual(ad.mask_topology((r > 8) & (r < 12)), (1, 1))
        self.assertEqual(ad.mask_topology(r < 12), (1, 0))

    def test_pieces_and_border_background(self):
        m = np.zeros((20, 30), dtype=bool)
        m[2:6, 2:6] = True
        m[10:18, 10:28] = True
        m[12:16, 12:16] = False  # a hole
        m[0:20, 29] = True  # touches the border: the background to its left is no hole
        self.assertEqual(ad.mask_topology(m), (3, 1))
        diag = np.eye(6, dtype=bool)  # 8-connected: one piece
        self.assertEqual(ad.mask_topology(diag)[0], 1)
        self.assertEqual(ad.label_mask(diag, diagonal=False)[1], 6)

    def test_projected_sphere_radius(self):
        R, D, H = 8.0, 32.0, 320
        alpha = math.asin(R / D)
        r_px = math.tan(alpha) / math.tan(math.radians(22.5)) * H / 2
        self.assertAlmostEqual(ad.sphere_radius_from_mask_area(math.pi * r_px ** 2, D, H), R, places=9)


class ContinuumRadius(unittest.TestCase):
    def test_lone_kernel_value(self):
        # a lone particle's iso radius at T = 0.2 is 0.975 Rc / 3
        rc = 3.0
        self.assertAlmostEqual(float(ad.kernel_value(0.975, rc)), 0.2, delta=2e-4)
        self.assertEqual(float(ad.kernel_value(rc, rc)), 0.0)

    def test_bulk_field_and_iso_radius(self):
        # deep inside a large ball the field is the kernel's integral: π Rc³ (1/3 − 2/5 + 1/7) / d³
        rc, d = 2.0, 1.0
        bulk = ad.continuum_field(0.0, 50.0, 1.0 / d ** 3, rc)
        self.assertAlmostEqual(bulk, math.pi * rc ** 3 * (1 / 3 - 2 / 5 + 1 / 7), places=4)
        # half the bulk on a flat surface (a very large ball), so T = 0.2 lies outside it
        self.assertAlmostEqual(ad.continuum_field(1000.0, 1000.0, 1.0, rc) / (bulk / 2), 1.0, places=2)
        r = ad.continuum_iso_radius(8.0, d, rc, 0.2)
        self.assertGreater(r, 8.0)
        self.assertLess(r, 8.0 + rc)
        self.assertAlmostEqual(ad.continuum_field(r, 8.0, 1.0, rc), 0.2, places=6)


class Parsing(unittest.TestCase):
    def test_render_stage_ms(self):
        out = """render voxel: 50000 particles from x.xyz, 640x360, radius 1 m (spacing 1 m, estimated), GL 4.5 / llvmpipe
  spacing estimate          11.04 ms (CPU)
  anisotropy (CPU)          31.93 ms
  upload particles           0.53 ms
  draw                     429.46 ms
    splat                   32.23 ms
  all frames (2 + 1 warm-up) 2066.56 ms
  GPU memory                12.00 MiB (the renderer's targets and buffers)
  anisotropic kernels: 39693 of 50000 stretched
"""
        total, aniso = ad.render_stage_ms(out)
        self.assertAlmostEqual(total, 31.93 + 0.53 + 429.46)
        self.assertAlmostEqual(aniso, 31.93)
        self.assertEqual(ad.STRETCHED.search(out).groups(), ("39693", "50000"))

    def test_kernel_flags(self):
        k = ad.Kernel("kr8", "k_r 8", "anisotropic", kr=8.0, lam=0.0)
        self.assertIsNone(k.flags({"--in"}))
        self.assertEqual(k.flags({"--kernel", "--kr", "--ks", "--kn", "--lambda"}),
                         ["--kernel", "anisotropic", "--kr", "8", "--ks", "1", "--kn", "25", "--lambda", "0"])
        self.assertEqual(ad.Kernel("iso", "isotropic").flags({"--in"}), [])
        self.assertEqual(ad.Kernel("iso", "isotropic").flags({"--kernel"}), ["--kernel", "isotropic"])

    def test_figure_sets_are_deterministic(self):
        a, b = ad.figure_sets(), ad.figure_sets()
        for k in a:
            np.testing.assert_array_equal(a[k], b[k])
        self.assertEqual(len(a["pool"]), 24 * 4 * 24)
        self.assertEqual(len(a["sheet"]), 1600)
        self.assertEqual(len(a["jet2"]), 240)


if __name__ == "__main__":
    unittest.main()
