"""The Python module against the command line: the same state hashes, the
same GI maps bit for bit, layers without copies, the engine's errors as
Python exceptions.

Usage: test_terrain.py PATH_TO_TERRAIN_CLI  (the module on PYTHONPATH)
"""
import gc
import os
import re
import subprocess
import sys
import tempfile
import unittest

import numpy as np

import terrain

CLI = None  # set from argv


def cli(*args):
    done = subprocess.run([CLI, *args], capture_output=True, text=True)
    if done.returncode != 0:
        raise AssertionError(f"terrain {' '.join(args)} failed: {done.stderr}")
    return done.stdout


def cli_hash(scene, size, ticks):
    out = cli("sim", "--scene", scene, "--size", str(size), "--ticks", str(ticks), "--hash-every", str(ticks),
              "--quiet")
    return re.search(rf"tick {ticks} hash ([0-9a-f]{{16}})", out).group(1)


def field_heights(ny=48, nx=64):
    """A non-square field (rows != columns catches a transposition) with ridges and a pit."""
    y, x = np.mgrid[0:ny, 0:nx].astype(np.float32)
    h = 300.0 * np.sin(x / 7.0) * np.cos(y / 5.0) + 2.0 * x - 400.0 * np.exp(-((x - 40) ** 2 + (y - 20) ** 2) / 50.0)
    return h.astype(np.float32)


class SimulationMatchesCli(unittest.TestCase):
    def test_erosion_hash(self):
        sim = terrain.Simulation(terrain.builtin_scene("erosion", size=64))
        sim.tick(25, threads=2)
        self.assertEqual(sim.tick_count, 25)
        self.assertGreater(sim.time, 0.0)
        self.assertEqual(sim.state_hash(), cli_hash("erosion", 64, 25))

    def test_waves_hash_ticked_one_by_one(self):
        sim = terrain.Simulation(terrain.builtin_scene("waves", size=48, seed=1))
        for _ in range(6):
            sim.tick()
        self.assertEqual(sim.state_hash(), cli_hash("waves", 48, 6))

    def test_scene_file_hash(self):
        path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scenes", "pit-lake.toml")
        sim = terrain.Simulation(terrain.load_scene(path, size=40, seed=3))
        sim.tick(5)
        out = cli("sim", "--scene", path, "--size", "40", "--seed", "3", "--ticks", "5", "--hash-every", "5",
                  "--quiet")
        self.assertIn(f"tick 5 hash {sim.state_hash()}", out)

    def test_scene_properties(self):
        scene = terrain.builtin_scene("erosion", size=32, seed=7)
        self.assertEqual((scene.name, scene.nx, scene.ny, scene.seed), ("erosion", 32, 32, 7))
        self.assertGreater(scene.cell_size, 0.0)
        self.assertIn("hydraulic", scene.stages)


class LayersAreViews(unittest.TestCase):
    def test_no_copy_and_kept_alive(self):
        sim = terrain.Simulation(terrain.builtin_scene("erosion", size=32))
        bedrock = sim.layer("bedrock")
        water = sim.layers()["water"]
        self.assertEqual(bedrock.shape, (32, 32))
        self.assertEqual(bedrock.dtype, np.float32)
        self.assertTrue(bedrock.flags.c_contiguous)
        self.assertFalse(bedrock.flags.writeable)
        with self.assertRaises(ValueError):
            bedrock[0, 0] = 1.0
        before = water.copy()
        address = water.__array_interface__["data"][0]
        sim.tick(3)
        # the same storage, updated in place by the ticks
        self.assertTrue(np.shares_memory(water, sim.layer("water")))
        self.assertEqual(sim.layer("water").__array_interface__["data"][0], address)
        self.assertFalse(np.array_equal(before, water))
        ground = sim.ground()
        np.testing.assert_array_equal(ground, sim.layer("bedrock") + sim.layer("soil"))
        # the array keeps the simulation alive
        expected = water.copy()
        del sim
        gc.collect()
        np.testing.assert_array_equal(water, expected)

    def test_layer_sets_and_shapes(self):
        erosion = terrain.Simulation(terrain.builtin_scene("erosion", size=32)).layers()
        self.assertEqual(set(erosion), {"bedrock", "soil", "water", "suspended", "fluxL", "fluxR", "fluxT",
                                        "fluxB", "velX", "velY"})
        waves = terrain.Simulation(terrain.builtin_scene("waves", size=32)).layers()
        self.assertEqual(waves["faceU"].shape, (32, 33))
        self.assertEqual(waves["faceV"].shape, (33, 32))
        self.assertNotIn("suspended", waves)


class FrameLayersMatchCli(unittest.TestCase):
    def test_frame_layers_are_the_frames_the_cli_writes(self):
        sim = terrain.Simulation(terrain.builtin_scene("erosion", size=32))
        sim.tick(20)
        layers = sim.frame_layers()
        self.assertEqual(list(layers), ["height", "bedrock", "soil", "water", "sediment", "discharge", "velocity",
                                        "sediment_flux", "erosion", "deposition", "net_erosion", "wetness"])
        self.assertTrue(np.all((layers["wetness"] >= 0.0) & (layers["wetness"] <= 1.0)))
        self.assertTrue(np.array_equal(layers["height"], sim.ground()))
        with tempfile.TemporaryDirectory() as tmp:
            cli("sim", "--scene", "erosion", "--size", "32", "--ticks", "20", "--out", tmp, "--format", "exr",
                "--quiet")
            height, cell = terrain.read_heightmap(os.path.join(tmp, "frame_000020.exr"))
            self.assertTrue(np.array_equal(height, layers["height"]))
            self.assertEqual(cell, sim.scene.cell_size)
            vdb = os.path.join(tmp, "python.vdb")
            sim.write_vdb(vdb)
            height, cell = terrain.read_heightmap(vdb)
            self.assertTrue(np.array_equal(height, layers["height"]))


class GiMatchesCli(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.tmp = self.dir.name
        # heights as the command reads them: a 16-bit PNG read back by the engine's reader
        png = os.path.join(self.tmp, "h.png")
        self.z = terrain.write_png_heightmap(png, field_heights())
        self.heights, cell = terrain.read_heightmap(png, *self.z)
        self.assertIsNone(cell)
        self.png = png

    def tearDown(self):
        self.dir.cleanup()

    def path(self, name):
        return os.path.join(self.tmp, name)

    def run_cli(self, *flags):
        cli("gi", "--heightmap", self.png, "--z-scale", repr(self.z[0]), "--z-offset", repr(self.z[1]),
            "--cell-size", "12.5", *flags)

    def same_file(self, a, b):
        with open(a, "rb") as fa, open(b, "rb") as fb:
            self.assertEqual(fa.read(), fb.read(), f"{a} and {b} differ")

    def test_indirect_frame_bit_identical(self):
        key = "135,30,3,1,0.95,0.9"
        self.run_cli("--light", "sunsky", "--key", key, "--bounces", "2", "--subsample", "2", "--threads", "2",
                     "--indirect-kernel", "blocker", "--out-ambient", self.path("cli_ambient.npy"),
                     "--out-indirect", self.path("cli_indirect.npy"), "--out-shade", self.path("cli_shade.tif"))
        maps = terrain.gi(self.heights, 12.5, light="sunsky", key=[key], bounces=2, subsample=2, threads=2,
                          indirect_kernel="blocker", out_shade=self.path("py_shade.tif"))
        self.assertEqual(maps["shade"].shape, (48, 64, 3))
        self.assertEqual(maps["ambient"].shape, (48, 64))
        self.assertTrue(np.array_equal(maps["ambient"], np.load(self.path("cli_ambient.npy"))))
        self.assertTrue(np.array_equal(maps["indirect"], np.load(self.path("cli_indirect.npy"))))
        self.assertGreater(float(maps["indirect"].max()), 0.0)
        # the shade at full precision: the command's GeoTIFF, the module's (written from C++ and from numpy)
        self.same_file(self.path("cli_shade.tif"), self.path("py_shade.tif"))
        terrain.write_geotiff(self.path("np_shade.tif"), maps["shade"])
        self.same_file(self.path("cli_shade.tif"), self.path("np_shade.tif"))
        # and the module's ambient through the engine's .npy writer
        terrain.write_npy(self.path("np_ambient.npy"), maps["ambient"])
        self.same_file(self.path("cli_ambient.npy"), self.path("np_ambient.npy"))

    def test_defaults_and_any_thread_count(self):
        self.run_cli("--out-ambient", self.path("cli_ambient.npy"), "--out-shade", self.path("cli_shade.exr"))
        one = terrain.gi(self.heights, 12.5, threads=1)
        two = terrain.gi(self.heights, 12.5, threads=2)
        self.assertNotIn("indirect", one)
        self.assertTrue(np.array_equal(one["ambient"], np.load(self.path("cli_ambient.npy"))))
        for name in ("shade", "ambient"):
            self.assertTrue(np.array_equal(one[name], two[name]))
        terrain.write_exr(self.path("np_shade.exr"), one["shade"])
        self.same_file(self.path("cli_shade.exr"), self.path("np_shade.exr"))

    def test_strided_input_is_read_as_is(self):
        wide = np.zeros((48, 128), np.float32)
        wide[:, ::2] = self.heights
        strided = terrain.gi(wide[:, ::2], 12.5, subsample=2)
        plain = terrain.gi(np.ascontiguousarray(self.heights), 12.5, subsample=2)
        self.assertTrue(np.array_equal(strided["ambient"], plain["ambient"]))


class ErrorsAreExceptions(unittest.TestCase):
    def test_bad_arrays(self):
        h = field_heights(16, 16)
        with self.assertRaisesRegex(TypeError, "float32"):
            terrain.gi(h.astype(np.float64), 10.0)
        with self.assertRaisesRegex(TypeError, "numpy array"):
            terrain.gi(h.tolist(), 10.0)
        with self.assertRaisesRegex(ValueError, "2 dimensions"):
            terrain.gi(h[None], 10.0)
        bad = h.copy()
        bad[3, 5] = np.nan
        with self.assertRaisesRegex(ValueError, "row 3, column 5"):
            terrain.gi(bad, 10.0)
        with self.assertRaisesRegex(ValueError, "side"):
            terrain.gi(h[:1], 10.0)

    def test_bad_options_carry_the_commands_message(self):
        h = field_heights(16, 16)
        with self.assertRaisesRegex(ValueError, "--bounces"):
            terrain.gi(h, 10.0, bounces=-1)
        with self.assertRaisesRegex(ValueError, "--brdf"):
            terrain.gi(h, 10.0, brdf="velvet")
        with self.assertRaisesRegex(ValueError, "no_such_flag|no-such-flag"):
            terrain.gi(h, 10.0, no_such_flag=1)
        with self.assertRaisesRegex(ValueError, "input file"):
            terrain.gi(h, 10.0, heightmap="x.png")
        with self.assertRaisesRegex(ValueError, "cell_size"):
            terrain.gi(h, 0.0)

    def test_engine_errors(self):
        with self.assertRaisesRegex(ValueError, "erosion"):
            terrain.builtin_scene("no-such-scene")
        with self.assertRaisesRegex(ValueError, "size"):
            terrain.builtin_scene("erosion", size=0)
        with self.assertRaises(OSError):
            terrain.load_scene("/nonexistent/scene.toml")
        with self.assertRaises(OSError):
            terrain.read_heightmap("/nonexistent/heights.png")
        with self.assertRaises(OSError):
            terrain.write_npy("/nonexistent/a.npy", np.zeros((2, 2), np.float32))
        sim = terrain.Simulation(terrain.builtin_scene("erosion", size=16))
        with self.assertRaisesRegex(ValueError, "faceU.*not allocated"):
            sim.layer("faceU")
        with self.assertRaisesRegex(ValueError, "no layer"):
            sim.layer("lava")
        with self.assertRaises(ValueError):
            sim.tick(-1)
        with self.assertRaisesRegex(ValueError, "threads"):
            sim.tick(1, threads=-1)
        self.assertEqual(sim.tick_count, 0)


if __name__ == "__main__":
    CLI = sys.argv.pop(1)
    unittest.main()
