# The Python module rll (python/rll_module.cpp): every function, its errors, and its renders
# against the command line's. Run by ctest (label python) with PYTHONPATH at the module and
# RLL_BINARY the `rll` program.
import json
import os
import signal
import subprocess
import threading
import time

import numpy as np
import pytest

import rll

RLL = os.environ.get("RLL_BINARY", "rll")
BOX = "builtin:cornell-box"


def cli(*args, check=True):
    r = subprocess.run([RLL, *args], capture_output=True, text=True)
    if check:
        assert r.returncode == 0, r.stderr
    return r


@pytest.fixture(scope="module")
def box():
    return rll.load(BOX, res=(40, 30))


def test_scenes_and_samplers():
    scenes = rll.scenes()
    assert "cornell-box" in scenes and "furnace" in scenes
    assert all(isinstance(d, str) and d for d in scenes.values())
    listed = [line.split()[0] for line in cli("scenes").stdout.splitlines()]
    assert list(scenes) == listed
    assert rll.samplers() == cli("samplers").stdout.split()
    assert {"rll", "power", "uniform", "tree"} <= set(rll.samplers())


def test_load_matches_the_cli_stats(box, tmp_path):
    stats = tmp_path / "s.json"
    cli("render", BOX, "--res", "40x30", "--spp", "1", "--quiet", "-o", str(tmp_path / "x.exr"),
        "--stats", str(stats))
    s = json.loads(stats.read_text())
    assert box.lights == s["lights"] and box.lights >= 2
    assert box.triangles == s["triangles"]
    assert box.resolution == (40, 30)
    lo, hi = box.bounds
    assert all(a < b for a, b in zip(lo, hi))
    assert box.source == BOX
    assert "cornell-box" in repr(box)
    assert rll.load(BOX, res="20x10").resolution == (20, 10)


def test_load_errors_carry_rlls_message(tmp_path):
    missing = str(tmp_path / "nope.pbrt")
    with pytest.raises(rll.Error) as e:
        rll.load(missing)
    assert isinstance(e.value, RuntimeError)
    assert "nope.pbrt" in str(e.value)
    # The same message as `rll render` prints for it.
    r = cli("render", missing, "-o", str(tmp_path / "x.exr"), check=False)
    assert r.returncode != 0 and str(e.value) in r.stderr
    with pytest.raises(rll.Error, match="cornell-box"):  # lists the builtin names
        rll.load("builtin:no-such-scene")
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nf 1 2 3\n")
    with pytest.raises(rll.Error, match="bad.obj"):
        rll.load(bad)  # a PathLike is taken too
    with pytest.raises(rll.Error, match="res"):
        rll.load(BOX, res="40by30")
    with pytest.raises(rll.Error, match="res"):
        rll.load(BOX, res=(0, 30))
    with pytest.raises(rll.Error, match="res"):
        rll.load(BOX, res=[1, 2, 3])


def test_render_shape_and_stats(box):
    r = rll.render(box, sampler="power", spp=4, threads=2)
    assert isinstance(r.image, np.ndarray)
    assert r.image.dtype == np.float32 and r.image.shape == (30, 40, 3)
    assert np.isfinite(r.image).all() and (r.image >= 0).all() and r.image.mean() > 0
    assert r.spp == 4 and r.seconds > 0 and not r.interrupted
    s = r.stats
    assert s["spp"] == 4 and s["sampler"]["name"] == "power" and s["threads"] == 2
    assert s["rays"]["camera"] == 40 * 30 * 4 == s["samples"]
    assert s["rays"]["total"] == sum(s["rays"][k] for k in ("camera", "bounce", "shadow"))
    assert s["lights"] == box.lights and s["resolution"] == (40, 30)
    assert "40x30, 4 spp" in repr(r)
    # res overrides the scene's film for this render.
    assert rll.render(box, spp=1, res=(16, 8)).image.shape == (8, 16, 3)


ROOM = "builtin:cornell-boxes-room"


@pytest.mark.parametrize(
    "scene,sampler,integrator,depth,params,seed",
    [(BOX, "rll", "path", 5, {}, 1), (BOX, "power", "direct", 5, {}, 7),
     (ROOM, "rll", "path", 3, {"rll.cut_size": 4, "path.strategy": "nee"}, 3)],
)
def test_render_equals_the_cli(tmp_path, scene, sampler, integrator, depth, params, seed):
    out = tmp_path / "cli.exr"
    sets = [a for k, v in params.items() for a in ("--set", f"{k}={v}")]
    cli("render", scene, "--res", "40x30", "--spp", "6", "--seed", str(seed), "--sampler", sampler,
        "--integrator", integrator, "--max-depth", str(depth), "--quiet", "-o", str(out), *sets)
    loaded = rll.load(scene, res=(40, 30))
    r = rll.render(loaded, sampler=sampler, integrator=integrator, max_depth=depth, spp=6,
                   seed=seed, params=params)
    ref = rll.read_exr(out)
    assert r.image.shape == ref.shape
    assert np.array_equal(r.image, ref)  # to the bit
    # Another seed, or leaving the parameters out, gives another image: the comparison can fail.
    other = rll.render(loaded, sampler=sampler, integrator=integrator, max_depth=depth, spp=6,
                       seed=seed + 1, params=params)
    assert not np.array_equal(other.image, ref)
    if params:
        plain = rll.render(loaded, sampler=sampler, integrator=integrator, spp=6, seed=seed)
        assert not np.array_equal(plain.image, ref)
        assert r.stats["max_depth"] == depth and plain.stats["max_depth"] == 5


def test_render_errors_name_the_parameter(box):
    with pytest.raises(rll.Error, match="sampler: .*no-such"):
        rll.render(box, sampler="no-such", spp=1)
    with pytest.raises(rll.Error, match="rll.no_such_key"):
        rll.render(box, spp=1, params={"rll.no_such_key": 1})
    with pytest.raises(rll.Error, match="nee.candidates"):
        rll.render(box, spp=1, params={"nee.candidates": 0})
    with pytest.raises(rll.Error, match="integrator"):
        rll.render(box, spp=1, integrator="bdpt")
    with pytest.raises(rll.Error, match="max_depth"):
        rll.render(box, spp=1, max_depth=0)
    with pytest.raises(rll.Error, match="spp"):
        rll.render(box, spp=0)
    with pytest.raises(rll.Error, match="time"):
        rll.render(box, spp=1, time=-1)
    with pytest.raises(rll.Error, match="threads"):
        rll.render(box, spp=1, threads=-1)
    with pytest.raises(rll.Error, match="progress"):
        rll.render(box, spp=1, progress=3)
    with pytest.raises(rll.Error, match="res"):
        rll.render(box, spp=1, res="x")


def test_progress_callback(box):
    calls = []
    r = rll.render(box, spp=12, progress=lambda p: calls.append(dict(p)))
    assert calls and calls[-1]["spp"] == 12 == r.spp
    assert len(calls) == r.stats["passes"]
    spps = [c["spp"] for c in calls]
    assert spps == sorted(spps) and spps[0] >= 1
    assert all(c["spp_target"] == 12 for c in calls)

    def boom(p):
        raise ValueError("from the callback")

    with pytest.raises(ValueError, match="from the callback"):
        rll.render(box, spp=12, progress=boom)


def test_time_budget(box):
    r = rll.render(box, spp=1 << 20, time=0.3)
    assert 1 <= r.spp < 1 << 20 and r.stats["out_of_time"] and not r.interrupted


def test_ctrl_c_stops_a_render_and_returns_what_it_has(box):
    # SIGINT to this process while the render runs with the GIL released, no callback given.
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    t0 = time.monotonic()
    timer.start()
    try:
        r = rll.render(box, spp=1 << 20, res=(64, 48))
    finally:
        timer.cancel()
    assert r.interrupted and r.stats["interrupted"]
    assert 1 <= r.spp < 1 << 20
    assert time.monotonic() - t0 < 30
    assert r.image.shape == (48, 64, 3) and r.image.mean() > 0


def test_error_matches_the_cli(box, tmp_path):
    a = rll.render(box, spp=2, seed=1).image
    b = rll.render(box, spp=64, seed=2).image
    pa, pb = tmp_path / "a.exr", tmp_path / "b.exr"
    rll.write_exr(pa, a)
    rll.write_exr(pb, b)
    want = json.loads(cli("error", str(pa), str(pb), "--json").stdout)
    got = rll.error(a, b)
    assert set(got) == set(want)
    for k in ("relmse", "trimmed_relmse", "mrse", "mse"):
        assert got[k] == pytest.approx(want[k], rel=1e-12) and got[k] > 0
    assert rll.error(b, b)["relmse"] == 0
    var = np.full_like(b, 1e-4)
    noisy = rll.error(a, b, reference_variance=var)
    assert noisy["reference_noise_subtracted"] and noisy["mse"] == pytest.approx(got["mse"] - 1e-4)
    # float64 and nested lists are taken too.
    assert rll.error(a.astype(np.float64), b.tolist())["mse"] == pytest.approx(got["mse"])


def test_error_rejects_bad_images():
    img = np.ones((4, 5, 3), np.float32)
    with pytest.raises(rll.Error, match="4x5|5x4"):
        rll.error(img, np.ones((5, 4, 3), np.float32))
    with pytest.raises(rll.Error, match="img: expected an HxWx3 array"):
        rll.error(np.ones((4, 5, 4)), img)
    with pytest.raises(rll.Error, match="ref"):
        rll.error(img, np.ones((4, 5)))
    neg = img.copy()
    neg[1, 2, 0] = -1
    with pytest.raises(rll.Error, match="ref"):
        rll.error(img, neg)
    nan = img.copy()
    nan[0, 0, 1] = np.nan
    with pytest.raises(rll.Error, match="img"):
        rll.error(nan, img)
    with pytest.raises(rll.Error, match="img"):
        rll.error("not an image", img)


def test_exr_round_trip(tmp_path):
    rng = np.random.default_rng(5)
    img = (rng.random((7, 9, 3)) * 100).astype(np.float32)
    img[0, 0] = [0, 1e-30, 3e30]
    p = tmp_path / "x.exr"
    rll.write_exr(p, img)
    back = rll.read_exr(str(p))
    assert back.dtype == np.float32 and back.shape == (7, 9, 3)
    assert np.array_equal(back, img)
    # A non-contiguous view is written as the array it shows.
    rll.write_exr(p, img[:, ::2])
    assert np.array_equal(rll.read_exr(p), img[:, ::2])
    with pytest.raises(rll.Error, match="missing.exr"):
        rll.read_exr(tmp_path / "missing.exr")
    with pytest.raises(rll.Error, match="image"):
        rll.write_exr(p, np.ones((3, 3)))
    with pytest.raises(rll.Error):
        rll.write_exr(tmp_path / "no-such-dir" / "x.exr", img)


def test_docstrings_and_stub():
    for f in (rll.load, rll.render, rll.error, rll.read_exr, rll.write_exr, rll.scenes,
              rll.samplers):
        assert f.__doc__ and len(f.__doc__) > 40
    assert issubclass(rll.Error, RuntimeError)
    stub = os.path.join(os.path.dirname(rll.__file__), "rll.pyi")
    text = open(stub).read()
    for name in ("def load", "def render", "def error", "def read_exr", "def write_exr",
                 "class Scene", "class Render", "class Error"):
        assert name in text
