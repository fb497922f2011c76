"""Whole-clip and Points declarations (pyrograph_plugin), ClipView, and the two examples that use
them, called as plain functions: studio.temporal_median and studio.csv_points."""

import pathlib
import weakref

import numpy as np
import pytest

from test_plugin_api import check_declaration_error, def_line, load, port, write

import pyrograph_plugin  # noqa: E402  (test_plugin_api put the host folder on sys.path)
from pyrograph_plugin import ClipView, FrameError  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[3]
TEMPORAL_MEDIAN = ROOT / "examples" / "plugins" / "temporal_median" / "plugins" / "temporal_median.py"
CSV_POINTS = ROOT / "examples" / "plugins" / "csv_emitter" / "plugins" / "csv_points.py"
EMITTERS = ROOT / "examples" / "plugins" / "csv_emitter" / "emitters.csv"


@pytest.fixture(scope="module")
def temporal_median():
    return load(TEMPORAL_MEDIAN).temporal_median


@pytest.fixture(scope="module")
def csv_points():
    return load(CSV_POINTS).csv_points


def test_temporal_median_declaration(temporal_median):
    assert temporal_median.__pyrograph__.as_dict() == {
        "type_name": "studio.temporal_median",
        "category": "Studio",
        "doc": "Removes sparks and single-frame flicker: each pixel becomes its median over nearby frames.",
        "time": "whole_clip",
        "function": "temporal_median",
        "line": def_line(TEMPORAL_MEDIAN, "def temporal_median("),
        "inputs": [
            port("clip", "clip", "Frames to clean"),
            port("radius", "int", "Frames on each side that vote", 2, [1, 8]),
        ],
        "outputs": [port("clip", "clip")],
    }


def test_csv_points_declaration(csv_points):
    assert csv_points.__pyrograph__.as_dict() == {
        "type_name": "studio.csv_points",
        "category": "Studio",
        "doc": "Reads emitter points from a CSV file: x, y, z and, when there is one, the seconds each starts.",
        "time": "per_frame",
        "function": "csv_points",
        "line": def_line(CSV_POINTS, "def csv_points("),
        "inputs": [
            port("path", "path", "CSV file with columns x,y,z and optionally seconds"),
            port("scale", "float", "Multiplies every position", 1.0, [1e-6, 1e6]),
            port("offset", "vec3", "Added to every position after scale", [0.0, 0.0, 0.0]),
        ],
        "outputs": [port("points", "points")],
    }


def test_a_whole_clip_node_takes_every_kind_and_clip_image_means_clip(tmp_path):
    path = write(tmp_path, """
        from pyrograph_plugin import node, Clip, Float, Image, Mask, Outputs, Points

        @node("test.mixed", time="whole_clip", doc="Mixed.")
        def mixed(a: Clip, b: Clip(Image, doc="Second"), c: Clip(doc="Third"), still: Image, matte: Mask,
                  gain: Float = 1.0) -> Outputs(clip=Clip(Image), image=Image, points=Points, total=Float):
            ...

        @node("test.points", doc="Per-frame points.")
        def points() -> Points(doc="Where"):
            ...
    """)
    module = load(path)
    declaration = module.mixed.__pyrograph__.as_dict()
    assert declaration["time"] == "whole_clip"
    assert declaration["inputs"] == [
        port("a", "clip"), port("b", "clip", "Second"), port("c", "clip", "Third"),
        port("still", "image", channels="any"), port("matte", "mask"), port("gain", "float", default=1.0),
    ]
    assert declaration["outputs"] == [
        port("clip", "clip"), port("image", "image", channels="any"), port("points", "points"), port("total", "float"),
    ]
    assert module.points.__pyrograph__.as_dict()["outputs"] == [port("points", "points", "Where")]


# As in test_plugin_api: @node arguments, parameters, return annotation, the parameter the
# message must name (or None) and words it must hold.
WHOLE = '"test.f", time="whole_clip"'
ERRORS = {
    "clip_input_per_frame": ('"test.f"', "x: Clip", "-> Image", "x", "pyrograph applies it to every frame"),
    "clip_output_per_frame": ('"test.f"', "x: Image", "-> Clip", None, "output 'clip': a Clip needs @node(..., time="),
    "clip_in_outputs_per_frame": ('"test.f"', "x: Image", "-> Outputs(a=Image, b=Clip)", None, "output 'b': a Clip needs"),
    "points_input": ('"test.f"', "x: Points", "-> Image", "x", "Points inputs are not supported yet"),
    "points_input_whole_clip": (WHOLE, "x: Points", "-> Clip", "x", "Points inputs are not supported yet"),
    "clip_default": (WHOLE, "x: Clip = None", "-> Clip", "x", "a Clip input cannot have a default"),
    "clip_of_gray_images": (WHOLE, "x: Clip(Image(channels='gray'))", "-> Clip", "x", "any channels"),
    "clip_of_a_mask": (WHOLE, "x: Clip(Mask)", "-> Clip", "x", "any channels"),
    "clip_doc_positional": (WHOLE, "x: Clip('Frames')", "-> Clip", "x", "Clip(doc='Frames')"),
    "clip_output_bad": (WHOLE, "x: Clip", "-> Clip(Mask)", None, "any channels"),
}


@pytest.mark.parametrize("case", ERRORS.values(), ids=ERRORS.keys())
def test_clip_and_points_declaration_errors(tmp_path, case):
    check_declaration_error(tmp_path, case)


def test_a_clip_view_acts_like_a_read_only_list_of_frames():
    frames = [np.full((2, 3), i, np.float32) for i in range(5)]
    view = ClipView(frames, fps=12)
    assert len(view) == 5 and view.fps == 12.0 and isinstance(view.fps, float)
    assert view[0] is frames[0] and view[-1] is frames[4] and view[np.int64(2)] is frames[2]
    assert [f[0, 0] for f in view] == [0, 1, 2, 3, 4]
    for bad in (5, -6):
        with pytest.raises(IndexError, match=f"frame {bad} is outside the clip of 5 frames"):
            view[bad]
    with pytest.raises(TypeError, match="one frame at a time"):
        view[1:3]
    with pytest.raises(TypeError):
        view[1.0]
    assert ClipView([]).fps == 24.0 and len(ClipView([])) == 0 and list(ClipView([])) == []
    assert repr(view) == "ClipView(5 frames at 12 fps)"
    assert issubclass(FrameError, Exception) and "FrameError" in pyrograph_plugin.__all__


def test_a_fetching_view_asks_for_each_index_it_is_given():
    asked = []
    view = ClipView._fetching(4, 30, lambda i: asked.append(i) or i * 10)
    assert (view[1], view[-1], view[-4], list(view)) == (10, 30, 0, [0, 10, 20, 30])
    assert asked == [1, 3, 0, 0, 1, 2, 3]


# ---------------------------------------------------------------------------------------------
# studio.temporal_median, called directly.


def expected_median(frames, radius):
    last = len(frames) - 1
    return [np.median(np.stack(frames[max(0, i - radius):min(last, i + radius) + 1]), axis=0) for i in range(len(frames))]


class CountingClip:
    """A clip that counts fetches and, through weak references, the frames still alive."""

    def __init__(self, frames):
        self.frames = frames
        self.fetched = []
        self.alive = []

    def fetch(self, i):
        self.fetched.append(i)
        frame = self.frames[i].copy()  # a fresh array each time, as the worker's are
        self.alive.append(weakref.ref(frame))
        return frame

    def held(self):
        return sum(ref() is not None for ref in self.alive)


@pytest.mark.parametrize("length, radius", [(12, 2), (7, 1), (3, 2), (1, 3), (20, 8)])
@pytest.mark.parametrize("shape", [(5, 6), (4, 3, 4)], ids=["gray", "rgba"])
def test_temporal_median_fetches_each_frame_once_and_holds_a_window(temporal_median, length, radius, shape):
    rng = np.random.default_rng(length * 10 + radius)
    frames = [rng.random(shape, dtype=np.float32) for _ in range(length)]
    frames[length // 2][0, 0] = 1000.0  # a spark on one frame only
    clip = CountingClip(frames)
    view = ClipView._fetching(length, 24.0, clip.fetch)
    out = []
    for frame in temporal_median(view, radius=radius):
        assert clip.held() <= 2 * radius + 1, "the window holds at most 2·radius+1 frames"
        out.append(frame)
    assert sorted(clip.fetched) == list(range(length)), "each frame fetched exactly once"
    assert all(f.dtype == np.float32 and f.shape == shape for f in out)
    for got, want in zip(out, expected_median(frames, radius)):
        np.testing.assert_array_equal(got, want)
    if length >= 3:
        assert np.all(out[length // 2][0, 0] < 1.0), "the one-frame spark is gone"


def test_temporal_median_holds_few_frames_of_a_long_clip(temporal_median):
    clip = CountingClip([np.full((2, 2), i, np.float32) for i in range(200)])
    most = 0
    for _ in temporal_median(ClipView._fetching(200, 24.0, clip.fetch), radius=3):
        most = max(most, clip.held())
    assert most == 7


# ---------------------------------------------------------------------------------------------
# studio.csv_points, called directly.


def test_csv_points_reads_the_example_ring(csv_points):
    points = csv_points(str(EMITTERS))
    assert points.dtype == np.float64 and points.shape == (12, 4)
    np.testing.assert_allclose(points[:, 0], np.arange(12) * 0.1, atol=1e-12)
    np.testing.assert_allclose(np.hypot(points[:, 1], points[:, 3]), 0.4, atol=1e-4)
    np.testing.assert_array_equal(points[:, 2], 0.05)
    moved = csv_points(str(EMITTERS), scale=2.0, offset=(1.0, 0.0, -1.0))
    np.testing.assert_allclose(moved[:, 1:], points[:, 1:] * 2 + [1.0, 0.0, -1.0])
    np.testing.assert_array_equal(moved[:, 0], points[:, 0])


def test_csv_points_takes_columns_in_any_order_comments_and_extra_columns(csv_points, tmp_path):
    path = write(tmp_path, """\
        # exported by layout.py
        Z, note, X,Y
        3, "a, quoted note", 1, 2   # first
        # skipped

        6,,4,5
    """, "points.csv")
    points = csv_points(str(path), scale=10.0, offset=(0.5, 0.0, 0.0))
    np.testing.assert_array_equal(points, [[10.5, 20, 30], [40.5, 50, 60]])
    assert points.shape == (2, 3) and points.dtype == np.float64


BAD_CSV = {
    "missing_column": ("x,y,seconds\n1,2,0\n", "no column 'z' in the header x,y,seconds"),
    "not_a_number": ("x,y,z\n1,2,3\n1,two,3\n", "points.csv:3: column 'y' holds 'two', which is not a finite number"),
    "nan": ("x,y,z\n1,nan,3\n", "points.csv:2: column 'y' holds 'nan'"),
    "short_row": ("x,y,z\n1,2\n", "points.csv:2: the row has no value in column 'z'"),
    "empty": ("", "the file has no header row"),
    "only_comments": ("# nothing yet\n\n", "the file has no header row"),
    "header_only": ("x,y,z\n", "no points below the header row"),
    "negative_seconds": ("seconds,x,y,z\n0,1,2,3\n-1,1,2,3\n", "points.csv:3: seconds must be 0 or more"),
    "twice": ("x,y,z,x\n1,2,3,4\n", "names the column 'x' twice"),
}


@pytest.mark.parametrize("case", BAD_CSV.values(), ids=BAD_CSV.keys())
def test_csv_points_errors_name_the_file_and_what_is_wrong(csv_points, tmp_path, case):
    text, words = case
    path = tmp_path / "points.csv"
    path.write_text(text)
    with pytest.raises(ValueError) as error:
        csv_points(str(path))
    assert str(path) in str(error.value) and words in str(error.value)


def test_csv_points_missing_file_is_an_os_error_naming_it(csv_points, tmp_path):
    with pytest.raises(FileNotFoundError, match="nowhere.csv"):
        csv_points(str(tmp_path / "nowhere.csv"))


def test_the_example_docs_name_their_render_commands():
    for path, graph in ((TEMPORAL_MEDIAN, "temporal_median/temporal-median.ron"), (CSV_POINTS, "csv_emitter/csv-emitter.ron")):
        assert f"pyrograph render examples/plugins/{graph} --out pyrograph-out" in path.read_text()
    assert EMITTERS.read_text().startswith("# ")
