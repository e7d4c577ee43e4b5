"""raylab.render and raylab.write_image: the command's pixels, progress, Ctrl-C, bad input."""

import _thread
import os
import pathlib
import subprocess
import sys
import threading

import numpy as np
import pytest

import raylab

REPOSITORY = pathlib.Path(
    os.environ.get("RAYLAB_REPOSITORY", pathlib.Path(__file__).resolve().parents[2])
)
CORNELL = REPOSITORY / "scenes/cornell-mitsuba.toml"


# The repository's PFM reader (rows from the top, as raylab's arrays have them).
sys.path.insert(0, str(REPOSITORY / "tools/mitsuba"))
from pfm import read_pfm  # noqa: E402


@pytest.mark.skipif("RAYLAB_BIN" not in os.environ, reason="needs the raylab command")
@pytest.mark.parametrize(
    "options, arguments",
    [
        (dict(), []),
        (dict(seed=7, sampler="multijitter"), ["--seed", "7", "--sampler", "multijitter"]),
        (dict(integrator="lab"), ["--integrator", "lab"]),
        (dict(integrator="path-scalar", max_depth=3), ["--integrator", "path-scalar",
                                                       "--max-depth", "3"]),
    ],
)
def test_the_same_pixels_as_raylab_render(tmp_path, options, arguments):
    output = tmp_path / "cli.pfm"
    command = [os.environ["RAYLAB_BIN"], "render", str(CORNELL), "--size", "48x36", "--spp",
               "3", "--threads", "2", "-o", str(output), *arguments]
    subprocess.run(command, check=True, capture_output=True)
    ours = raylab.render(CORNELL, size=(48, 36), spp=3, threads=1, **options)
    want = read_pfm(output)
    assert ours.image.shape == want.shape
    np.testing.assert_array_equal(ours.image.view(np.uint32), want.view(np.uint32))
    assert ours.samples == 3 and not ours.interrupted
    assert ours.image.mean() > 0


def test_aovs_and_a_region():
    whole = raylab.render(CORNELL, size=(40, 30), spp=2, aovs=["albedo", "depth"])
    assert set(whole.aovs) == {"albedo", "depth"}
    assert whole.aovs["depth"].shape == (30, 40, 3)
    part = raylab.render(CORNELL, size=(40, 30), spp=2, region=(10, 5, 30, 25), aovs="albedo")
    assert part.region == (10, 5, 30, 25) and part.image.shape == (20, 20, 3)
    np.testing.assert_array_equal(part.image, whole.image[5:25, 10:30])
    np.testing.assert_array_equal(part.aovs["albedo"], whole.aovs["albedo"][5:25, 10:30])


def test_the_lab_scene_by_default():
    lab = raylab.render(size=(50, 50))
    assert lab.samples == 1 and lab.image.shape == (50, 50, 3)
    assert 0 < lab.image.mean() < 1


def test_progress_goes_up_to_one():
    seen = []
    raylab.render(CORNELL, size=(128, 128), spp=96, threads=1, progress=seen.append)
    assert seen and seen[-1] == 1.0
    assert all(0 <= a <= b <= 1 for a, b in zip(seen, seen[1:]))
    # A render of a second or more reports on its way, not only at the end.
    assert any(0 < f < 1 for f in seen), seen


def test_an_exception_in_the_callback_stops_the_render():
    def fail(fraction):
        raise RuntimeError("enough")

    with pytest.raises(RuntimeError, match="enough"):
        raylab.render(CORNELL, size=(128, 128), spp=4096, progress=fail)


def test_ctrl_c_returns_the_passes_so_far():
    timer = threading.Timer(0.3, _thread.interrupt_main)
    timer.start()
    try:
        result = raylab.render(CORNELL, size=(128, 128), spp=100_000)
    finally:
        timer.cancel()
    assert result.interrupted
    assert 1 <= result.samples < 100_000
    assert np.isfinite(result.image).all() and result.image.mean() > 0


def test_write_image(tmp_path):
    image = np.random.default_rng(1).random((12, 20, 3), dtype=np.float32) * 2
    raylab.write_image(tmp_path / "a.pfm", image)
    np.testing.assert_array_equal(read_pfm(tmp_path / "a.pfm"), image)
    raylab.write_image(tmp_path / "a.exr", image)
    assert (tmp_path / "a.exr").read_bytes()[:4] == b"\x76\x2f\x31\x01"
    raylab.write_image(tmp_path / "a.png", image, exposure=-1, tone_map="aces")
    assert (tmp_path / "a.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    raylab.write_image(tmp_path / "gray.pfm", image[:, :, 0])
    np.testing.assert_array_equal(read_pfm(tmp_path / "gray.pfm")[:, :, 2], image[:, :, 0])


@pytest.mark.parametrize(
    "call, error, words",
    [
        (lambda: raylab.render("no-such-scene"), ValueError, "no-such-scene"),
        (lambda: raylab.render("missing.toml"), OSError, "missing.toml"),
        (lambda: raylab.render(spp=0), ValueError, "spp"),
        (lambda: raylab.render(spp=1.5), TypeError, "spp"),
        (lambda: raylab.render(size=(10,)), ValueError, "size"),
        (lambda: raylab.render(integrator="magic"), ValueError, "magic"),
        (lambda: raylab.render(aovs=["colour"]), ValueError, "colour"),
        (lambda: raylab.render(size=(10, 10), region=(0, 0, 20, 5)), ValueError, "region"),
        (lambda: raylab.render(progress=3), TypeError, "progress"),
        (lambda: raylab.write_image("x.bmp", np.zeros((2, 2, 3))), ValueError, "x.bmp"),
        (lambda: raylab.write_image("/no/such/dir/x.png", np.zeros((2, 2, 3))), OSError, "x.png"),
        (lambda: raylab.write_image("x.pfm", np.zeros((2, 2, 4))), ValueError, "image"),
    ],
)
def test_bad_input(call, error, words):
    with pytest.raises(error) as raised:
        call()
    assert words in str(raised.value)


@pytest.mark.parametrize("example", ["depth_image.py", "visibility.py", "render_png.py"])
def test_the_readmes_examples_run(tmp_path, example):
    script = REPOSITORY / "python/examples" / example
    environment = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [os.path.dirname(os.path.dirname(raylab.__file__)), os.environ.get("PYTHONPATH", "")]))
    arguments = {
        "depth_image.py": [str(REPOSITORY / "crates/raylab/tests/data/meshes/bunny.obj.gz"),
                           str(tmp_path / "depth.png")],
        "visibility.py": [str(REPOSITORY / "crates/raylab/tests/data/meshes/bunny.obj.gz")],
        "render_png.py": [str(CORNELL), str(tmp_path / "render.png")],
    }[example]
    done = subprocess.run([sys.executable, str(script), *arguments], cwd=tmp_path,
                          env=environment, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    if example == "depth_image.py":
        assert (tmp_path / "depth.png").read_bytes()[:4] == b"\x89PNG"
    if example == "render_png.py":
        assert (tmp_path / "render_albedo.png").exists() and (tmp_path / "render.exr").exists()
