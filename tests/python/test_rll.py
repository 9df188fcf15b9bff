# The Python module rll (python/rll_module.cpp): every function, its errors, and its renders
# against the command line's. Run by ctest (label python) with PYTHONPATH at the module and
# RLL_BINARY the `rll` program.
import json
import os
import signal
import subprocess
import sys
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
    # SIGINT to this process while the render runs with the GIL released, 0.5 s after its first
    # pass (the callback only times the signal: a signal before any pass would stop the render
    # with nothing in it, and loading the scene at this size takes a while).
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))

    def first_pass(p):
        if p["passes"] == 1:
            timer.start()

    t0 = time.monotonic()
    try:
        r = rll.render(box, spp=1 << 20, res=(64, 48), progress=first_pass)
    finally:
        timer.cancel()
    assert r.interrupted and r.stats["interrupted"]
    assert 1 <= r.spp < 1 << 20
    assert time.monotonic() - t0 < 30
    assert r.image.shape == (48, 64, 3) and r.image.mean() > 0


def test_ctrl_c_stops_inside_a_long_pass():
    # One pass of 1024 spp (12.6 M samples at 128x96, seconds on two cores; a tile of it 262,144
    # samples): SIGINT a second in stops the render within a bound, not at the end of the pass,
    # and it returns what it has, each pixel with the samples it took (Render.counts).
    sent = []

    def interrupt():
        sent.append(time.monotonic())
        os.kill(os.getpid(), signal.SIGINT)

    scene = rll.load(BOX, res=(128, 96))
    timer = threading.Timer(1.0, interrupt)
    timer.start()
    try:
        r = rll.render(scene, spp=1024, pass_spp=1024, max_pass_spp=1024)
    finally:
        timer.cancel()
    done = time.monotonic()
    assert r.interrupted and sent
    assert done - sent[0] < 4.0, "the render did not stop inside its pass"
    assert r.stats["passes"] == 1
    counts = r.counts
    assert r.spp == counts.min() == 0, "the pass ran to its end"
    assert counts.sum() > 0
    assert ((counts > 0) & (counts < 1024)).any(), "threads finished their pixels or tiles first"
    assert np.isfinite(r.image).all() and (r.image[counts == 0] == 0).all()


def test_render_checks_its_pass_sizes(box):
    with pytest.raises(rll.Error, match=r"pass_spp: 0 is not in \[1, 1024\]"):
        rll.render(box, spp=1, pass_spp=0)
    with pytest.raises(rll.Error, match="max_pass_spp: 0"):
        rll.render(box, spp=1, max_pass_spp=0)


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


@pytest.fixture(scope="module")
def learnt(box):
    return rll.render(box, sampler="rll", spp=16, seed=3)


def test_state_arrays(box, learnt):
    st = learnt.state
    assert isinstance(st, rll.State) and st.sampler == "rll" and st.passes >= 1
    assert st.lights == box.lights
    cells = st.cells
    n = len(cells["id"])
    assert n >= 1 and (np.diff(cells["id"].astype(np.int64)) > 0).all()
    assert (cells["id"] < st.capacity).all()
    assert cells["key"].dtype == np.uint64 and (cells["key"] != 0).all()
    assert len(set(cells["key"].tolist())) == n  # one cell per key
    assert cells["anchor"].shape == (n, 3) and cells["normal"].shape == (n, 3)
    assert np.allclose(np.linalg.norm(cells["normal"], axis=1), 1, atol=1e-4)
    lo, hi = np.array(box.bounds[0]), np.array(box.bounds[1])
    pad = 1e-3 * np.linalg.norm(hi - lo)
    assert ((cells["anchor"] >= lo - pad) & (cells["anchor"] <= hi + pad)).all()
    assert (cells["rewards"] >= 0).all() and cells["rewards"].max() > 0
    assert cells["learnt"].dtype == bool and cells["learnt"].any()
    assert ((cells["defensive"] >= 0) & (cells["defensive"] <= 1)).all()
    assert "rll.State of rll" in repr(st)
    # The light tree: the root covers every light, children partition their parent.
    t = st.tree
    m = len(t["power"])
    assert t["lo"].shape == (m, 3) and t["begin"][0] == 0 and t["end"][0] == box.lights
    inner = np.nonzero(~t["leaf"])[0]
    for i in inner:
        c = t["child"][i]
        assert t["parent"][c] == i and t["parent"][c + 1] == i
        assert t["begin"][c] == t["begin"][i] and t["end"][c] == t["begin"][c + 1]
        assert t["end"][c + 1] == t["end"][i]
    assert (t["end"][t["leaf"]] - t["begin"][t["leaf"]] == 1).all()
    assert (t["power"] >= 0).all() and t["power"][0] > 0
    assert t["parent"][0] == 2**32 - 1
    init = st.initial_cut
    assert len(init) >= 1 and t["begin"][init[0]] == 0 and t["end"][init[-1]] == box.lights


def test_state_probabilities_match_the_sampler_pmf(learnt):
    st = learnt.state
    cells = st.cells
    with_cut = cells["id"][cells["size"] > 0]
    assert len(with_cut) >= 1
    checked_single = 0
    for cell in with_cut[:40]:
        cut = st.cut(cell)
        assert cut["own"]
        k = len(cut["nodes"])
        assert k == cells["size"][cells["id"] == cell][0]
        # The clusters partition the lights in order.
        assert cut["begin"][0] == 0 and cut["end"][-1] == st.lights
        assert (cut["begin"][1:] == cut["end"][:-1]).all()
        p = cut["probability"]
        assert p.dtype == np.float32 and (p >= 0).all()
        assert abs(p.astype(np.float64).sum() - 1) < 1e-5
        pmf = st.pmf(cell)  # every light, at the cell's anchor
        assert pmf.shape == (st.lights,)
        for j in range(k):
            b, e = cut["begin"][j], cut["end"][j]
            if e - b == 1:  # one light: its pmf is the cluster's probability, to the bit
                assert st.pmf(cell, int(b)) == p[j]
                checked_single += 1
            assert pmf[b:e].astype(np.float64).sum() == pytest.approx(float(p[j]), rel=1e-5,
                                                                        abs=1e-7)
        assert abs(pmf.astype(np.float64).sum() - 1) < 1e-5
    assert checked_single > 0
    # The probabilities differ between cells: the check compares learnt tables, not one prior.
    tables = {tuple(st.cut(c)["probability"].round(6)) for c in with_cut[:40]}
    assert len(tables) > 1


def test_state_errors_and_other_samplers(box, learnt, tmp_path):
    st = learnt.state
    with pytest.raises(rll.Error, match="cell"):
        st.cut(st.capacity)
    with pytest.raises(rll.Error, match="light"):
        st.pmf(int(st.cells["id"][0]), st.lights)
    with pytest.raises(rll.Error, match="point"):
        st.pmf(int(st.cells["id"][0]), 0, point=(1, 2))
    assert rll.render(box, sampler="power", spp=1).state is None
    assert rll.render(box, sampler="fermat", spp=2).state.sampler == "fermat"
    oracle = rll.render(box, sampler="oracle", spp=1, params={"oracle.discovery_spp": 1}).state
    assert oracle.sampler == "oracle" and (oracle.cells["size"] > 0).any()


def test_state_save_and_load(box, learnt, tmp_path):
    st = learnt.state
    path = tmp_path / "s.state"
    st.save(path)
    back = rll.load_state(path, box)
    for k in ("id", "key", "anchor", "level", "rewards", "size"):
        assert np.array_equal(back.cells[k], st.cells[k]), k
    cell = int(st.cells["id"][st.cells["size"] > 0][0])
    assert np.array_equal(back.cut(cell)["probability"], st.cut(cell)["probability"])
    assert np.array_equal(back.pmf(cell), st.pmf(cell))
    # The CLI loads what Python saved, and Python what the CLI saved.
    cli("render", BOX, "--res", "40x30", "--spp", "2", "--quiet", "-o", str(tmp_path / "x.exr"),
        "--rll-state", str(path), "--rll-state-mode", "load")
    saved = tmp_path / "cli.state"
    cli("render", BOX, "--res", "40x30", "--spp", "4", "--quiet", "-o", str(tmp_path / "y.exr"),
        "--rll-state", str(saved), "--rll-state-mode", "save")
    assert rll.load_state(saved, box).passes >= 1
    with pytest.raises(rll.Error, match="s.state"):
        rll.load_state(path, box, sampler="fermat")
    with pytest.raises(rll.Error, match="missing.state"):
        rll.load_state(tmp_path / "missing.state", box)
    with pytest.raises(rll.Error, match="sampler: .*power"):
        rll.load_state(path, box, sampler="power")


def test_exr_count_channel_and_share_header(tmp_path):
    out = tmp_path / "cli.exr"
    cli("render", BOX, "--res", "20x10", "--spp", "3", "--sampler", "power", "--quiet", "-o",
        str(out))
    img, info = rll.read_exr(out, metadata=True)
    assert img.shape == (10, 20, 3)
    assert info["count"].dtype == np.uint32 and info["count"].shape == (10, 20)
    assert (info["count"] == 3).all()
    share = info["share"]
    assert share["settings"]["sampler"] == "power" and share["settings"]["resolution"] == "20x10"
    assert "rll.share" in info["attributes"] and info["channels"] == {}
    # Written back with its counts and header, rll merge takes it as the share it was.
    copy = tmp_path / "copy.exr"
    rll.write_exr(copy, img, count=info["count"], share=share, attributes={"note": "hi"})
    img2, info2 = rll.read_exr(copy, metadata=True)
    assert np.array_equal(img2, img) and np.array_equal(info2["count"], info["count"])
    assert info2["share"] == share and info2["attributes"]["note"] == "hi"
    merged = tmp_path / "merged.exr"
    cli("merge", str(merged), str(copy), "--check-against", str(out))
    # A render's counts are the CLI's count channel.
    r = rll.render(rll.load(BOX, res=(20, 10)), sampler="power", spp=3)
    assert np.array_equal(r.counts, info["count"])
    assert isinstance(rll.read_exr(copy, metadata=False), np.ndarray)
    with pytest.raises(rll.Error, match="count"):
        rll.write_exr(copy, img, count=np.ones((3, 3)))
    with pytest.raises(rll.Error, match="attributes"):
        rll.write_exr(copy, img, attributes={"a": 1})
    assert rll.read_exr(tmp_path / "copy.exr", metadata=True)[1]["share"] == share


def test_reference_and_compare_match_the_cli(tmp_path):
    cache = tmp_path / "cache"
    scene = rll.load(BOX, res=(24, 16))
    ref = rll.reference(scene, spp=16, cache_dir=cache)
    assert ref["source"] == "rendered" and ref["spp"] >= 16 and ref["sampler"] == "tree"
    assert ref["image"].shape == (16, 24, 3) and ref["variance"].shape == (16, 24, 3)
    again = rll.reference(scene, spp=16, cache_dir=cache)
    assert again["source"] == "cache" and np.array_equal(again["image"], ref["image"])
    cached = rll.read_exr(again["cache_entry"])
    assert np.array_equal(cached, ref["image"])

    out = tmp_path / "cmp"
    cli("compare", BOX, "--res", "24x16", "--samplers", "power,rll", "--spp", "4",
        "--repeats", "2", "--reference-spp", "16", "--cache-dir", str(cache), "--quiet",
        "--out", str(out))
    want = json.loads((out / "summary.json").read_text())
    got = rll.compare(scene, ["power", "rll"], spp=4, repeats=2, reference_spp=16,
                      cache_dir=cache)
    assert got["order"] == want["order"] and got["repeats"] == 2
    assert got["reference"]["source"] == "cache"
    assert got["reference"]["noise_relmse"] == pytest.approx(want["reference"]["noise_relmse"])
    assert [s["name"] for s in got["samplers"]] == ["power", "rll"]
    for g, w in zip(got["samplers"], want["samplers"]):
        assert set(g) <= set(w)
        missing = set(w) - set(g)
        assert missing <= {"image", "error_image"}, missing
        for metric in ("relmse", "trimmed_relmse", "mrse", "mse", "visible_sample_ratio"):
            assert g[metric]["values"] == pytest.approx(w[metric]["values"], rel=1e-9), metric
        assert g["spp"] == w["spp"]
    assert np.array_equal(got["images"]["power"], rll.read_exr(out / want["samplers"][0]["image"]))
    assert np.array_equal(got["reference_image"], rll.read_exr(out / "reference.exr"))
    # A given reference (array or file), and the errors.
    fixed = rll.compare(scene, ["power"], spp=2, reference=ref["image"])
    assert fixed["reference"]["source"] == "array"
    assert fixed["samplers"][0]["relmse"]["median"] == pytest.approx(
        rll.error(fixed["images"]["power"], ref["image"])["relmse"])
    with pytest.raises(rll.Error, match="budget"):
        rll.compare(scene, ["power"], reference=ref["image"])
    with pytest.raises(rll.Error, match="budget"):
        rll.compare(scene, ["power"], spp=2, time=1, reference=ref["image"])
    with pytest.raises(rll.Error, match="twice"):
        rll.compare(scene, ["power", "power"], spp=2, reference=ref["image"])
    with pytest.raises(rll.Error, match="sampler: .*nope"):
        rll.compare(scene, ["nope"], spp=2, reference=ref["image"])
    with pytest.raises(rll.Error, match="reference: the image is 3x2"):
        rll.compare(scene, ["power"], spp=2, reference=np.ones((2, 3, 3)))
    with pytest.raises(rll.Error, match="spp"):
        rll.reference(scene, spp=0, cache_dir=cache)


# Two lamps over a floor: lamp A (3x the power of B) inside a closed box, lamp B inside a box open
# at the bottom that the camera looks down into. Every floor point the camera sees faces lamp B,
# unoccluded, and can never reach lamp A: power sampling picks B with probability 1/4, so exactly
# that share of its light samples reaches a light.
OCCLUSION_SCENE = {
    "camera": {"position": [0, 0.8, 0], "target": [0, 0, 0], "up": [0, 0, 1], "fov": 40},
    "film": {"width": 48, "height": 48},
    "materials": {
        "white": {"albedo": [0.5, 0.5, 0.5]},
        "dim": {"albedo": [0, 0, 0], "emission": [10, 10, 10]},
        "bright": {"albedo": [0, 0, 0], "emission": [30, 30, 30]},
    },
    "shapes": [
        {"type": "quad", "origin": [-1.5, 0, -1.5], "edge1": [0, 0, 3], "edge2": [5.5, 0, 0],
         "material": "white"},
        {"type": "box", "min": [-1, 0.001, -1], "max": [1, 1, 1], "inward": True,
         "skip": ["-y"], "material": "white"},
        {"type": "quad", "origin": [-0.1, 0.95, -0.1], "edge1": [0.2, 0, 0],
         "edge2": [0, 0, 0.2], "material": "dim"},
        {"type": "box", "min": [2.5, 0.001, -0.5], "max": [3.5, 1, 0.5], "inward": True,
         "material": "white"},
        {"type": "quad", "origin": [2.9, 0.95, -0.1], "edge1": [0.2, 0, 0],
         "edge2": [0, 0, 0.2], "material": "bright"},
    ],
}


@pytest.fixture(scope="module")
def occlusion(tmp_path_factory):
    path = tmp_path_factory.mktemp("occ") / "occlusion.json"
    path.write_text(json.dumps(OCCLUSION_SCENE))
    return path


def test_aov_visible_ratio_of_power_is_the_analytic_share(occlusion):
    scene = rll.load(occlusion)
    spp = 64
    r = rll.render(scene, sampler="power", integrator="direct", spp=spp, aov=["visible"])
    vis = r.aov["visible"]
    assert vis.shape == (48, 48) and vis.dtype == np.float32 and np.isfinite(vis).all()
    # Every pixel takes one light sample per sample: the mean of the pixels' ratios is the share
    # of all N samples. Binomial bound, z = 4.5 (Sobol' points stratify the choice: tighter still);
    # it is 3.5% of 1/4, so a 5% bias of the ratio fails.
    n = vis.size * spp
    share = 0.25
    bound = 4.5 * np.sqrt(share * (1 - share) / n)
    assert abs(vis.mean() - share) < bound, (vis.mean(), bound)
    assert bound < 0.05 * share
    # The whole render's ratio (--stats) is the same share: only floor points are seen.
    assert r.stats["rays"]["shadow"] == n
    # rll learns that lamp A never reaches: its ratio is far higher.
    learnt = rll.render(scene, sampler="rll", integrator="direct", spp=spp, aov="visible")
    assert learnt.aov["visible"].mean() > 0.6


def test_aov_cell_image_is_constant_inside_cells(occlusion):
    scene = rll.load(occlusion)
    r = rll.render(scene, sampler="rll", integrator="direct", spp=8, aov="cell,entropy,rewards")
    cell = r.aov["cell"]
    assert (cell >= 0).all() and (cell == np.round(cell)).all()
    ids = np.unique(cell)
    assert len(ids) >= 4  # cell boundaries cross the view
    # The floor is cut by axis-aligned cell boxes, which the camera (looking straight down, up +z)
    # sees as rectangles: each id holds a rectangle, constant inside (its last sample decides a
    # pixel on a boundary, so one pixel of its edge may show the neighbour).
    widths = []
    for c in ids:
        ys, xs = np.nonzero(cell == c)
        y0, y1, x0, x1 = ys.min(), ys.max(), xs.min(), xs.max()
        inner = cell[y0 + 1:y1, x0 + 1:x1]
        assert (inner == c).all(), c
        if x0 > 0 and x1 < 47:
            widths.append(x1 - x0 + 1)
    # One level of detail: one cell size (a level apart would be twice the width); perspective
    # and the ragged edges vary it by a little.
    assert widths and max(widths) <= 1.5 * min(widths)
    st = r.state
    in_state = set(st.cells["id"].tolist())
    assert set(ids.astype(int).tolist()) <= in_state
    # Every cell of the image lies on the floor (anchor y = 0, normal up).
    rows = np.isin(st.cells["id"], ids.astype(np.uint32))
    assert np.allclose(st.cells["anchor"][rows, 1], 0, atol=1e-3)
    assert np.allclose(st.cells["normal"][rows], [0, 1, 0], atol=1e-3)
    # Entropy and rewards of each pixel's cell, as the state has them.
    ent, rew = r.aov["entropy"], r.aov["rewards"]
    c0 = int(ids[0])
    p = st.cut(c0)["probability"].astype(np.float64)
    p = p[p > 0]
    where = cell == c0
    assert ent[where] == pytest.approx(-(p * np.log2(p)).sum(), rel=1e-5)
    assert (rew[where] == st.cells["rewards"][st.cells["id"] == c0][0]).all()
    colours = rll.cell_colours(cell)
    assert colours.shape == (48, 48, 3) and (colours > 0).all()


def test_aov_leaves_the_image_unchanged_and_matches_the_cli(occlusion, tmp_path):
    scene = rll.load(occlusion, res=(24, 24))
    names = list(rll.aov_names())
    assert names == ["cell", "probability", "entropy", "visible", "rewards"]
    plain = rll.render(scene, sampler="rll", spp=6, seed=2)
    with_aov = rll.render(scene, sampler="rll", spp=6, seed=2, aov=names)
    assert np.array_equal(plain.image, with_aov.image)  # to the bit
    assert plain.aov == {} and sorted(with_aov.aov) == sorted(names)
    prob = with_aov.aov["probability"]
    assert ((prob > 0) & (prob <= 1)).all()
    out = tmp_path / "aov.exr"
    cli("render", str(occlusion), "--res", "24x24", "--spp", "6", "--seed", "2", "--quiet",
        "--aov", ",".join(names), "-o", str(out))
    img, info = rll.read_exr(out, metadata=True)
    assert np.array_equal(img, plain.image)
    assert sorted(info["channels"]) == sorted("aov." + n for n in names)
    for n in names[1:]:
        assert np.array_equal(info["channels"]["aov." + n], with_aov.aov[n], equal_nan=True), n
    # Cell ids are the table's, handed out in the order threads first reach the cells: the same
    # cells, not the same numbers, in another run; one id of one is one id of the other.
    pairs = set(zip(info["channels"]["aov.cell"].ravel().tolist(), with_aov.aov["cell"].ravel().tolist()))
    assert len({a for a, _ in pairs}) == len({b for _, b in pairs}) == len(pairs) > 1
    # Samplers without cells: no cell, entropy or rewards (-1, NaN), a probability and a ratio.
    power = rll.render(scene, sampler="power", spp=2, aov=names).aov
    assert (power["cell"] == -1).all() and np.isnan(power["entropy"]).all()
    assert np.isfinite(power["visible"]).all()


def test_aov_names_are_checked(box, tmp_path):
    with pytest.raises(rll.Error, match="aov: unknown diagnostic 'nope' .*cell, probability"):
        rll.render(box, spp=1, aov=["cell", "nope"])
    with pytest.raises(rll.Error, match="twice"):
        rll.render(box, spp=1, aov="cell,cell")
    with pytest.raises(rll.Error, match="megakernel"):
        rll.render(box, spp=1, aov="cell", wavefront=True)
    r = cli("render", BOX, "--res", "8x8", "--spp", "1", "--aov", "bogus", "-o",
            str(tmp_path / "x.exr"), check=False)
    assert r.returncode != 0 and "--aov: unknown diagnostic 'bogus'" in r.stderr
    assert "cell, probability, entropy, visible, rewards" in r.stderr
    r = cli("render", BOX, "--res", "8x8", "--spp", "1", "--aov", "cell", "-o",
            str(tmp_path / "x.png"), check=False)
    assert r.returncode != 0 and ".exr" in r.stderr


def test_wavefront_from_python_equals_the_cli(tmp_path):
    out = tmp_path / "wf.exr"
    cli("render", BOX, "--res", "24x16", "--spp", "4", "--sampler", "power", "--wavefront",
        "--quiet", "-o", str(out))
    r = rll.render(rll.load(BOX, res=(24, 16)), sampler="power", spp=4, wavefront=True)
    assert r.stats["renderer"] == "wavefront"
    assert np.array_equal(r.image, rll.read_exr(out))


def test_filter_psf_from_python_equals_the_cli(tmp_path):
    out = tmp_path / "psf.exr"
    cli("render", BOX, "--res", "24x16", "--spp", "3", "--sampler", "power", "--filter", "psf",
        "--set", "psf.width=2", "--quiet", "-o", str(out))
    box = rll.load(BOX, res=(24, 16))
    r = rll.render(box, sampler="power", spp=3, filter="psf", params={"psf.width": 2})
    assert np.array_equal(r.image, rll.read_exr(out))
    f = r.stats["filter"]
    assert f["name"] == "psf" and f["width"] == 2 and f["batches"] == 3
    assert 0 < f["cells_used"] < f["paths_filtered"]
    assert rll.render(box, sampler="power", spp=3).stats["filter"] == {"name": "none"}
    with pytest.raises(rll.Error, match="filter"):
        rll.render(box, spp=1, filter="bilateral")
    with pytest.raises(rll.Error, match="psf.width"):
        rll.render(box, spp=1, filter="psf", params={"psf.width": 0})


@pytest.mark.parametrize("script,args,says", [
    ("convergence.py", ["builtin:cornell-box", "--samplers", "power,rll", "--spp", "4",
                        "--res", "32x24", "--reference-spp", "16"], "rll: 4 spp"),
    ("cell_vs_oracle.py", ["builtin:cornell-boxes-room", "--spp", "8", "--res", "32x24"],
     "pmf sums: rll 1.0000"),
])
def test_examples_run(tmp_path, script, args, says):
    examples = os.path.join(os.path.dirname(__file__), "..", "..", "examples")
    out = tmp_path / "plot.png"
    env = dict(os.environ, RLL_CACHE_DIR=str(tmp_path / "cache"))
    r = subprocess.run([sys.executable, os.path.join(examples, script), *args, "--out", str(out)],
                       capture_output=True, text=True, env=env, cwd=tmp_path, timeout=240)
    assert r.returncode == 0, r.stderr
    assert says in r.stdout, r.stdout
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 5000


def test_install_puts_the_program_and_the_module_under_the_prefix(tmp_path):
    build = os.environ.get("RLL_BUILD_DIR")
    if not build:
        pytest.skip("RLL_BUILD_DIR (set by ctest) names no build folder")
    prefix = tmp_path / "prefix"
    r = subprocess.run(["cmake", "--install", build, "--prefix", str(prefix)],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    program = prefix / "bin" / "rll"
    assert subprocess.run([str(program), "samplers"], capture_output=True,
                          text=True).stdout.split() == rll.samplers()
    site = prefix / "lib" / f"python{sys.version_info.major}.{sys.version_info.minor}" / \
        "dist-packages"
    assert (site / "rll.pyi").exists()
    env = dict(os.environ, PYTHONPATH=str(site))
    r = subprocess.run([sys.executable, "-c", "import rll; print(rll.__file__, len(rll.samplers()))"],
                       capture_output=True, text=True, env=env)
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith(str(site)) and int(r.stdout.split()[1]) == len(rll.samplers())


# --- Hardening (issue 42): None and wrong types, Ctrl-C, memory, paths, messages, interpreter ---

STUB = os.path.join(os.path.dirname(rll.__file__), "rll.pyi")


def stub_parameters():
    """Every function and State method of the stub, with each parameter and whether it takes
    None (a None default, or an overload that takes None)."""
    import ast
    tree = ast.parse(open(STUB).read())
    found = {}

    def add(name, fn):
        params = found.setdefault(name, {})
        args = fn.args.args + fn.args.kwonlyargs
        defaults = [None] * (len(fn.args.args) - len(fn.args.defaults)) + fn.args.defaults + \
            fn.args.kw_defaults
        for a, d in zip(args, defaults):
            if a.arg == "self":
                continue
            takes_none = isinstance(d, ast.Constant) and d.value is None
            params[a.arg] = params.get(a.arg, False) or takes_none

    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            add(node.name, node)
        elif isinstance(node, ast.ClassDef) and node.name == "State":
            for f in node.body:
                if isinstance(f, ast.FunctionDef) and not any(
                        isinstance(d, ast.Name) and d.id == "property" for d in f.decorator_list):
                    add("State." + f.name, f)
    return found


STUB_PARAMS = stub_parameters()
NONE_CASES = [(fn, arg) for fn, params in STUB_PARAMS.items() for arg, takes_none in
              params.items() if not takes_none]

# A call of each function that succeeds, quickly; the cases replace one argument by None. Run in
# a subprocess, so that a crash of the interpreter is seen (and the case it died at).
NONE_SCRIPT = r"""
import json, os, sys, traceback
import numpy as np
import rll
tmp = sys.argv[1]
cases = json.loads(sys.argv[2])
box = rll.load("builtin:cornell-box", res=(8, 6))
img = np.ones((6, 8, 3), np.float32)
st = rll.render(box, sampler="rll", spp=2).state
exr = os.path.join(tmp, "a.exr")
rll.write_exr(exr, img)
st.save(os.path.join(tmp, "s.state"))
cell = int(st.cells["id"][0])
valid = {
    "scenes": (rll.scenes, {}), "samplers": (rll.samplers, {}), "aov_names": (rll.aov_names, {}),
    "load": (rll.load, dict(path="builtin:cornell-box", res=(8, 6))),
    "render": (rll.render, dict(scene=box, sampler="power", integrator="path", max_depth=2,
                                spp=1, seed=1, params={}, threads=1, wavefront=False,
                                device="cpu", pass_spp=1, max_pass_spp=1)),
    "load_state": (rll.load_state, dict(path=os.path.join(tmp, "s.state"), scene=box,
                                        sampler="rll", params={})),
    "error": (rll.error, dict(img=img, ref=img)),
    "read_exr": (rll.read_exr, dict(path=exr, metadata=False)),
    "write_exr": (rll.write_exr, dict(path=os.path.join(tmp, "b.exr"), image=img,
                                      attributes={})),
    "cell_colours": (rll.cell_colours, dict(cells=np.zeros((2, 2)))),
    "reference": (rll.reference, dict(scene=box, spp=2, sampler="power", seed=5,
                                      integrator="path", max_depth=2, params={},
                                      cache_dir=os.path.join(tmp, "cache"), force=False,
                                      threads=1)),
    "compare": (rll.compare, dict(scene=box, samplers=["power"], spp=1, repeats=1, seed=1,
                                  reference=img, reference_spp=2, reference_sampler="power",
                                  integrator="path", max_depth=2, params={}, threads=1)),
    "State.cut": (st.cut, dict(cell=cell)),
    "State.pmf": (st.pmf, dict(cell=cell, light=0)),
    "State.save": (st.save, dict(path=os.path.join(tmp, "t.state"))),
}
checked = set()
for fn, arg in cases:
    out = {"case": [fn, arg]}
    if fn not in valid:
        out["error"] = "the test has no valid call of " + fn
    else:
        f, kwargs = valid[fn]
        if fn not in checked:
            f(**kwargs)  # the valid call works: the None case tests None, not another fault
            checked.add(fn)
        try:
            f(**dict(kwargs, **{arg: None}))
            out["error"] = "None was taken"
        except Exception as e:
            out["types"] = [t.__name__ for t in type(e).__mro__]
            out["is_rll_error"] = isinstance(e, rll.Error)
            out["message"] = str(e)
    print(json.dumps(out), flush=True)
"""


@pytest.fixture(scope="module")
def none_results(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("none")
    r = subprocess.run([sys.executable, "-c", NONE_SCRIPT, str(tmp), json.dumps(NONE_CASES)],
                       capture_output=True, text=True, timeout=120)
    results = {}
    for line in r.stdout.splitlines():
        d = json.loads(line)
        results[tuple(d["case"])] = d
    return results, r


def test_the_none_cases_cover_every_binding():
    public = {n for n in dir(rll) if not n.startswith("_") and callable(getattr(rll, n)) and
              not isinstance(getattr(rll, n), type)}
    assert public <= set(STUB_PARAMS), "functions missing from rll.pyi"
    for name in ("load_state", "render", "reference", "compare", "write_exr", "State.pmf"):
        assert any(fn == name for fn, _ in NONE_CASES), name
    assert ("load_state", "scene") in NONE_CASES and ("compare", "samplers") in NONE_CASES
    # Arguments that take None are not among the cases.
    assert ("render", "time") not in NONE_CASES and ("State.pmf", "light") not in NONE_CASES


@pytest.mark.parametrize("fn,arg", NONE_CASES, ids=[f"{f}-{a}" for f, a in NONE_CASES])
def test_none_is_refused_by_name(none_results, fn, arg):
    # rll.load_state(path, None) ended the interpreter with SIGSEGV (None made a null pointer).
    results, run = none_results
    if (fn, arg) not in results:
        pytest.fail(f"the interpreter died (exit {run.returncode}) at or before {fn}({arg}=None):"
                    f"\n{run.stderr[-2000:]}")
    d = results[(fn, arg)]
    assert "error" not in d, d["error"]
    assert "TypeError" in d["types"] and d["is_rll_error"], d
    assert d["message"].startswith(f"{fn}(): argument '{arg}' must be "), d["message"]
    assert d["message"].endswith("not None"), d["message"]


def test_none_subprocess_ran_every_case(none_results):
    results, run = none_results
    assert run.returncode == 0, run.stderr[-3000:]
    assert len(results) == len(NONE_CASES)


@pytest.mark.parametrize("call,names", [
    (lambda box: rll.render(box, spp=1, res=(1.5, 2)),
     "render(): argument 'res' must be (width, height), two ints, not one holding float"),
    (lambda box: rll.render(box, spp=1, aov=[1]),
     "render(): argument 'aov' must be a sequence of str, not one holding int"),
    (lambda box: rll.render(box, spp="4"), "render(): argument 'spp' must be an int, not str"),
    (lambda box: rll.render("builtin:cornell-box"),
     "render(): argument 'scene' must be an rll.Scene (rll.load(...)), not str"),
    (lambda box: rll.render(box, seed=-1), "render(): argument 'seed': -1 is not in [0, "),
    (lambda box: rll.render(box, max_depth=2**40), "render(): argument 'max_depth': "),
    (lambda box: rll.compare(box, "power", spp=1), "compare(): argument 'samplers' must be a list "
                                                   "of str, not str"),
    (lambda box: rll.compare(box, ["power", None], spp=1),
     "compare(): argument 'samplers' must be a list of str, not one holding None"),
    (lambda box: rll.render(box, spp=1, params={"rll.cut_size": None}),
     "render(): argument 'params': the value of 'rll.cut_size' is None: give a value"),
    (lambda box: rll.render(box, spp=1, sampler="power\0rll"),
     "render(): argument 'sampler': 'power\\x00rll' holds a NUL character (at 5)"),
    (lambda box: rll.render(box, spp=1, params={"rll.cut\udcff": 1}),
     "render(): argument 'params': 'rll.cut\\udcff' holds a character that UTF-8 cannot encode"),
    (lambda box: rll.compare(box, ["power"], spp=1, reference=[[1]]),
     "reference: expected an HxWx3 array"),
    (lambda box: rll.load_state("x.state", box, params=[("a", 1)]),
     "load_state(): argument 'params' must be a dict, not list"),
    (lambda box: rll.write_exr("x.exr", np.ones((2, 2, 3)), share={1, 2}),
     "write_exr(): argument 'share' must be a dict or None, not set"),
    (lambda box: rll.write_exr("x.exr", np.ones((2, 2, 3)), share={"a": {1, 2}}),
     "share: cannot be stored as JSON (Object of type set is not JSON serializable)"),
    (lambda box: rll.write_exr("x.exr", np.ones((2, 2, 3)), share={"a": float("nan")}),
     "share: cannot be stored as JSON"),
    (lambda box: rll.write_exr("x.exr", np.ones((2, 2, 3)), count=np.full((2, 2), -1)),
     "count: the sample counts must be whole numbers in [0, 4294967295]"),
    (lambda box: rll.write_exr("x.exr", np.ones((2, 2, 3)), attributes={1: "a"}),
     "write_exr(): argument 'attributes' must be a dict of str -> str, not one holding int"),
    (lambda box: rll.write_exr(3, np.ones((2, 2, 3))),
     "write_exr(): argument 'path' must be a path (str, bytes or os.PathLike), not int"),
    (lambda box: rll.error(np.full((2, 2, 3), "a"), np.ones((2, 2, 3))),
     "img: expected an HxWx3 array of numbers, got dtype <U1"),
], ids=["res-float", "aov-int", "spp-str", "scene-str", "seed-negative", "depth-huge",
        "samplers-str", "samplers-none-item", "params-none-value", "sampler-nul", "params-surrogate", "reference-list", "params-list", "share-set", "share-nested-set",
        "share-nan", "count-negative", "attribute-key", "path-int", "img-str-dtype"])
def test_wrong_arguments_are_named(box, tmp_path, monkeypatch, call, names):
    # pybind11's "Unable to cast Python instance ..." and "incompatible function arguments" named
    # neither the argument nor what it takes; json.dumps's TypeError named no argument.
    monkeypatch.chdir(tmp_path)
    with pytest.raises(rll.Error) as e:
        call(box)
    msg = str(e.value)
    assert names in msg, msg
    assert "Unable to cast" not in msg and "incompatible function arguments" not in msg
    assert not (tmp_path / "x.exr").exists()


def test_state_pmf_checks_a_point_before_converting_it(learnt):
    st = learnt.state
    cell = int(st.cells["id"][0])
    t0 = time.monotonic()
    with pytest.raises(rll.Error) as e:  # was converted to a list of 10^8 floats first
        st.pmf(cell, 0, point=np.broadcast_to(np.float32(0), (10**8,)))
    assert time.monotonic() - t0 < 1
    assert str(e.value) == "State.pmf(): argument 'point': expected 3 coordinates, got 100000000"
    with pytest.raises(TypeError) as e:
        st.pmf(cell, 0, normal="abc")
    assert str(e.value) == "State.pmf(): argument 'normal' must be three numbers or None, not str"
    with pytest.raises(TypeError) as e:
        st.pmf(cell, 0, normal=(0, "1", 0))
    assert "argument 'normal' must be three numbers, not one holding str" in str(e.value)
    with pytest.raises(TypeError, match=r"State.pmf\(\): argument 'light' must be an int, not str"):
        st.pmf(cell, "0")
    assert st.pmf(cell, 0, point=np.zeros(3), normal=[0, 1.0, np.float32(0)]) >= 0


def test_a_damaged_share_header_names_the_file_line_and_column(tmp_path):
    # The rll.share header was parsed by json.loads, whose bare JSONDecodeError reached the user.
    p = tmp_path / "damaged.exr"
    rll.write_exr(p, np.ones((2, 2, 3), np.float32), attributes={"rll.share": '{"a":\n  1,,}'})
    with pytest.raises(rll.Error) as e:
        rll.read_exr(p, metadata=True)
    msg = str(e.value)
    assert str(p) in msg and "rll.share header is not valid JSON (line 2, column 5" in msg, msg
    assert "without metadata" in msg
    assert rll.read_exr(p).shape == (2, 2, 3)  # the image is still read


def run_python(code, *args, timeout=60, env=None):
    return subprocess.run([sys.executable, "-c", code, *map(str, args)], capture_output=True,
                          text=True, timeout=timeout, env=env)


INTERRUPTED_SCRIPT = r"""
import sys, time
import rll
scene = rll.load("builtin:cornell-box", res=(64, 48))
cache = sys.argv[1]
try:
    print("ready", flush=True)
    if sys.argv[2] == "reference":
        rll.reference(scene, spp=1 << 20, cache_dir=cache, force=True)
    else:
        rll.compare(scene, ["power"], spp=1, reference_spp=1 << 20, cache_dir=cache)
    print("ran to its end", flush=True)
except KeyboardInterrupt:
    print("KeyboardInterrupt", flush=True)
"""


@pytest.mark.parametrize("what", ["reference", "compare"])
def test_ctrl_c_interrupts_a_reference(tmp_path, what):
    # rll.reference rendered 2^20 spp with Ctrl-C ignored; compare's reference render too.
    cache = tmp_path / "cache"
    p = subprocess.Popen([sys.executable, "-c", INTERRUPTED_SCRIPT, str(cache), what],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert p.stdout.readline().strip() == "ready"
        time.sleep(0.7)
        sent = time.monotonic()
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=10)
    finally:
        p.kill()
    assert time.monotonic() - sent < 5, "Ctrl-C was not seen promptly"
    assert p.returncode == 0 and out.strip() == "KeyboardInterrupt", (out, err)
    # Nothing half-rendered was stored as a reference.
    assert not cache.exists() or not list(cache.glob("*.exr"))


MEMORY_SCRIPT = r"""
import os, sys
import numpy as np
import rll
out = sys.argv[1]
huge = np.broadcast_to(np.float32(1), (20000, 20000, 3))   # 4.8 GB as an array, 4 bytes here
budget = np.broadcast_to(np.float32(1), (16000, 16000, 3))  # in the image limit, over the budget
small = np.ones((2, 2, 3), np.float32)
calls = [
    ("write_exr", lambda: rll.write_exr(out, huge)),
    ("error", lambda: rll.error(huge, huge)),
    ("error-ref", lambda: rll.error(small, huge)),
    ("error-budget", lambda: rll.error(budget, budget)),
    ("count", lambda: rll.write_exr(out, small,
                                    count=np.broadcast_to(np.uint64(1), (20000, 20000)))),
    ("cell_colours", lambda: rll.cell_colours(np.broadcast_to(np.float32(0), (100000, 100000)))),
]
for name, call in calls:
    try:
        call()
        print(name, "accepted", flush=True)
    except Exception as e:
        print(name, type(e).__name__, str(e).replace("\n", " "), flush=True)
# The peak resident memory of this process since its exec (getrusage's ru_maxrss would count
# the parent's at the fork).
peak = [l.split()[1] for l in open("/proc/self/status") if l.startswith("VmHWM:")]
print("peak_kib", peak[0] if peak else 0, flush=True)
"""


def test_huge_broadcast_arrays_are_refused_before_they_are_copied(tmp_path):
    # write_exr / error on a 20000x20000 broadcast array took 4.7 GB before their size check.
    # The child may use 3 GiB of address space (so that the old behaviour fails with a
    # MemoryError rather than taking the machine's memory), hence a budget of 2.4 GiB.
    limit = 3 << 30
    code = (f"import resource; resource.setrlimit(resource.RLIMIT_AS, ({limit}, {limit}))\n"
            + MEMORY_SCRIPT)
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    r = run_python(code, tmp_path / "x.exr", env=env)
    assert r.returncode == 0, r.stderr
    lines = dict(line.split(" ", 1) for line in r.stdout.splitlines())
    for name in ("write_exr", "error", "error-ref"):
        assert lines[name].startswith("ArgumentValueError "), (name, lines[name])
        assert "20000x20000 is larger than rll's image limit" in lines[name], lines[name]
    assert "error(): argument 'img' (16000x16000) needs 2.9 GiB, more than the 2.4 GiB" in \
        lines["error-budget"], lines["error-budget"]
    assert lines["count"].startswith("Error count: expected an HxW array of sample counts (2x2)")
    assert "100000x100000 is larger than rll's image limit" in lines["cell_colours"]
    assert 0 < int(lines["peak_kib"]) < 400 * 1024, "a refused array was copied first"
    assert not (tmp_path / "x.exr").exists()


AOV_MEMORY_SCRIPT = r"""
import resource, sys
resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))
import rll
scene = rll.load("builtin:cornell-box")
try:
    rll.render(scene, sampler="power", spp=1, res=(8000, 5000), aov=["visible"])
    print("accepted", flush=True)
except rll.Error as e:
    print("refused", str(e).replace("\n", " "), flush=True)
peak = [l.split()[1] for l in open("/proc/self/status") if l.startswith("VmHWM:")]
print("peak_kib", peak[0] if peak else 0, flush=True)
"""


def test_render_aov_memory_is_checked_with_the_film(tmp_path):
    # 8000x5000: the film alone (48 bytes a pixel, 1.8 GiB) is within the child's 2.4 GiB
    # budget, with the aov diagnostics (76 bytes a pixel, 2.8 GiB) it is not: refused by name
    # before anything is allocated, as `rll render --aov` refuses it (the binding checked the
    # film alone and then took the diagnostics' memory).
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    r = run_python(AOV_MEMORY_SCRIPT, env=env)
    assert r.returncode == 0, r.stderr
    lines = dict(line.split(" ", 1) for line in r.stdout.splitlines())
    assert "refused" in lines, r.stdout
    assert "aov diagnostics" in lines["refused"], lines["refused"]
    assert 0 < int(lines["peak_kib"]) < 1024 * 1024, "the film was allocated before the check"


def test_paths_as_bytes_and_pathlike(tmp_path, monkeypatch):
    # A bytes path was written as str(bytes): rll.write_exr(b"x.exr", ...) made "b'x.exr'".
    monkeypatch.chdir(tmp_path)
    img = np.ones((2, 3, 3), np.float32)
    rll.write_exr(b"x.exr", img)
    assert os.listdir(".") == ["x.exr"]
    assert np.array_equal(rll.read_exr(b"x.exr"), img)
    # A name that is not UTF-8 is the bytes given, as str (os.fsdecode) or bytes.
    name = b"\xff\xfe.exr"
    rll.write_exr(name, img * 2)
    assert name in os.listdir(b".")
    assert np.array_equal(rll.read_exr(os.fsdecode(name)), img * 2)

    class BytesPath:
        def __fspath__(self):
            return b"y.exr"

    rll.write_exr(BytesPath(), img)
    assert sorted(os.listdir(".")) == sorted(["x.exr", "y.exr", os.fsdecode(name)])
    scene = rll.load(b"builtin:cornell-box", res=(8, 6))
    assert scene.source == "builtin:cornell-box" and isinstance(scene.source, str)


NUL_CALLS = [
    ("write_exr", "path", lambda p, box, img, st: rll.write_exr(p, img)),
    ("read_exr", "path", lambda p, box, img, st: rll.read_exr(p)),
    ("load", "path", lambda p, box, img, st: rll.load(p)),
    ("load_state", "path", lambda p, box, img, st: rll.load_state(p, box)),
    ("State.save", "path", lambda p, box, img, st: st.save(p)),
    ("reference", "cache_dir", lambda p, box, img, st: rll.reference(box, spp=2, cache_dir=p)),
    ("compare", "reference",
     lambda p, box, img, st: rll.compare(box, ["power"], spp=1, reference=p)),
]


@pytest.mark.parametrize("fn,arg,call", NUL_CALLS, ids=[c[0] for c in NUL_CALLS])
@pytest.mark.parametrize("as_bytes", [False, True], ids=["str", "bytes"])
def test_a_path_with_a_nul_byte_is_refused(tmp_path, box, learnt, fn, arg, call, as_bytes):
    # write_exr("victim.exr\0.tmp.exr") overwrote victim.exr: the system reads a name up to NUL.
    victim = tmp_path / "victim.exr"
    rll.write_exr(victim, np.full((30, 40, 3), 0.5, np.float32))
    before = victim.read_bytes()
    p = str(victim) + "\0.tmp.exr"
    with pytest.raises(ValueError) as e:
        call(os.fsencode(p) if as_bytes else p, box, np.ones((30, 40, 3), np.float32),
             learnt.state)
    assert isinstance(e.value, rll.Error)
    msg = str(e.value)
    assert msg.startswith(f"{fn}(): argument '{arg}': ") and "NUL byte (at byte" in msg, msg
    assert victim.read_bytes() == before
    assert sorted(os.listdir(tmp_path)) == ["victim.exr"]


def test_the_fallback_module_names_the_interpreter():
    # rll.py beside the compiled module is what a Python that cannot load it (another version)
    # imports instead: it says which interpreter rll is for.
    import importlib.util
    path = os.path.join(os.path.dirname(rll.__file__), "rll.py")
    assert os.path.exists(path)
    spec = importlib.util.spec_from_file_location("rll_fallback", path)
    with pytest.raises(ImportError) as e:
        spec.loader.exec_module(importlib.util.module_from_spec(spec))
    msg = str(e.value)
    built_for = says_built_for(msg)
    assert f"PYTHONPATH={os.path.dirname(path)} {built_for}" in msg, msg


def says_built_for(msg):
    """The interpreter that a message "rll was built for X (Python ...)" names: this one."""
    import re
    m = re.match(r"rll was built for (\S+) \(Python \d+\.\d+", msg)
    assert m, msg
    assert os.path.realpath(m.group(1)) == os.path.realpath(sys.executable), msg
    return m.group(1)


def other_interpreter():
    """A python3 of another installation than this one (pyenv's first on PATH, say), or None."""
    import shutil
    seen = set()
    for name in ("python3", "python3.11", "python3.12", "python3.13", "python3.10", "python"):
        exe = shutil.which(name)
        if not exe or exe in seen:
            continue
        seen.add(exe)
        try:
            r = subprocess.run([exe, "-c", "import sys; print(sys.base_prefix)"],
                               capture_output=True, text=True, timeout=30)
        except (OSError, subprocess.TimeoutExpired):
            continue
        if r.returncode == 0 and os.path.realpath(r.stdout.strip()) != \
                os.path.realpath(sys.base_prefix):
            return exe
    return None


def test_another_interpreter_is_told_which_one_to_use():
    # PYTHONPATH=build/python python3 with pyenv's python3 first on PATH failed with "No module
    # named numpy" (or an ABI mismatch) at the first array.
    exe = other_interpreter()
    if exe is None:
        pytest.skip("no python3 of another installation on PATH")
    folder = os.path.dirname(rll.__file__)
    env = dict(os.environ, PYTHONPATH=folder)
    r = subprocess.run([exe, "-c", "import rll"], capture_output=True, text=True, env=env,
                       timeout=60)
    assert r.returncode != 0
    msg = r.stderr.strip().splitlines()[-1]
    assert msg.startswith("ImportError: "), r.stderr
    built_for = says_built_for(msg[len("ImportError: "):])
    assert f"run PYTHONPATH={folder} {built_for}" in msg, msg
    assert ", but this is " in msg and "cmake -DPython3_EXECUTABLE=" in msg, msg


def test_a_venv_without_numpy_is_told_what_to_do(tmp_path):
    # A venv of this very Python (so the same installation) that does not see its numpy: the
    # import says so, rather than "No module named numpy" at the first array.
    venv = tmp_path / "venv"
    r = subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)],
                       capture_output=True, text=True, timeout=60)
    if r.returncode != 0:
        pytest.skip("cannot make a venv here: " + r.stderr[-200:])
    folder = os.path.dirname(rll.__file__)
    r = subprocess.run([str(venv / "bin" / "python"), "-c", "import rll"], capture_output=True,
                       text=True, env=dict(os.environ, PYTHONPATH=folder), timeout=60)
    assert r.returncode != 0
    msg = r.stderr.strip().splitlines()[-1]
    assert msg.startswith(f"ImportError: rll needs numpy, which {venv}/bin/python (Python "), msg
    assert "--system-site-packages" in msg and f"run PYTHONPATH={folder} " in msg, msg
