"""Whole-clip cooks and Points outputs through the worker, with the test playing pyrograph: it
answers need_frame by writing the frame into the arena, and emit with ack after reading the frame
back, as pyrograph does."""

import json
import os
import pathlib
import shutil
import signal
import struct
import time

import numpy as np
import pytest

from test_host import Host, host, line_of, load_module, sha256  # noqa: F401  (host is a fixture)

ROOT = pathlib.Path(__file__).resolve().parents[3]
TEMPORAL_MEDIAN = ROOT / "examples" / "plugins" / "temporal_median" / "plugins" / "temporal_median.py"
CSV_POINTS = ROOT / "examples" / "plugins" / "csv_emitter" / "plugins" / "csv_points.py"
EMITTERS = ROOT / "examples" / "plugins" / "csv_emitter" / "emitters.csv"
OUT_OFFSET = 1 << 20  # past the inputs: emitted and requested frames go here

CLIP_NODES = '''
import numpy as np
from pyrograph_plugin import node, Clip, FrameError, Float, Image, Int, Mask, Outputs, Points

KEPT = []


@node("test.double", time="whole_clip", doc="Doubles every frame, fetching as it goes.")
def double(clip: Clip, gain: Float = 2.0) -> Clip:
    for i in range(len(clip)):
        yield clip[i] * np.float32(gain)


@node("test.raises_at_2", time="whole_clip", doc="Fails on its third frame.")
def raises_at_2(clip: Clip) -> Clip:
    for i, frame in enumerate(clip):
        if i == 2:
            raise ValueError("frame 2 is cursed")
        yield frame


@node("test.last", time="whole_clip", doc="The last frame, fetched by a negative index.")
def last(clip: Clip) -> Outputs(image=Image, count=Int, fps=Float):
    return clip[-1].copy(), len(clip), clip.fps


@node("test.writes_frame", time="whole_clip", doc="Tries to edit a frame it was given.")
def writes_frame(clip: Clip) -> Clip:
    frame = clip[0]
    frame[0, 0] = 1.0
    yield frame


@node("test.out_of_range", time="whole_clip", doc="Indexes past the end.")
def out_of_range(clip: Clip) -> Image:
    return clip[len(clip)]


@node("test.no_frames", time="whole_clip", doc="Returns an empty clip.")
def no_frames(clip: Clip) -> Clip:
    return []


@node("test.changing_shape", time="whole_clip", doc="Frame 3 is wider.")
def changing_shape(clip: Clip) -> Clip:
    return [np.zeros((4, 6 if i == 3 else 5), np.float32) for i in range(5)]


@node("test.float64_frame", time="whole_clip", doc="Frame 1 is float64.")
def float64_frame(clip: Clip) -> Clip:
    yield np.zeros((2, 2), np.float32)
    yield np.zeros((2, 2))


@node("test.several", time="whole_clip", doc="A clip, a mask, a count and another clip.")
def several(clip: Clip, still: Image, threshold: Float = 0.5) -> Outputs(
    bright=Clip, matte=Mask, count=Int, stack=Clip
):
    frames = [clip[i] for i in range(len(clip))]
    return {
        "bright": (f + still for f in frames),
        "matte": still > threshold,
        "count": len(frames),
        "stack": np.stack(frames)[::-1],
    }


@node("test.catches_frame_errors", time="whole_clip", doc="Skips frames pyrograph cannot make.")
def catches_frame_errors(clip: Clip) -> Clip:
    for i in range(len(clip)):
        try:
            yield clip[i]
        except FrameError:
            continue


@node("test.own_frame_error", time="whole_clip", doc="Raises a FrameError of its own.")
def own_frame_error(clip: Clip) -> Clip:
    raise FrameError("made up")


@node("test.swallows", time="whole_clip", doc="Catches everything.")
def swallows(clip: Clip) -> Int:
    try:
        clip[0]
    except Exception:
        pass
    return 1


@node("test.keeps_view", time="whole_clip", doc="Keeps its clip for later.")
def keeps_view(clip: Clip) -> Int:
    KEPT.append(clip)
    return len(KEPT)


@node("test.uses_kept_view", time="whole_clip", doc="Uses a clip kept from an earlier cook.")
def uses_kept_view() -> Image:
    return KEPT[0][0]


@node("test.points", doc="Points as returned.")
def points(which: Int = 0) -> Points:
    return [
        np.array([[0, 1, 2], [3, 4, 5]], np.int32),
        np.array([[0.5, 1, 2, 3]], np.float32),
        np.zeros((5, 2)),
        np.array([[0, 1, float("nan")]]),
        [[0, 1, 2]],
        np.zeros((0, 3)),
        np.array([[0, 1, 2, 3], [-1, 1, 2, 3]], np.float64),
        np.zeros((2, 3), bool),
    ][which]


@node("test.clip_and_points", time="whole_clip", doc="Points per frame.")
def clip_and_points(clip: Clip) -> Outputs(points=Points, clip=Clip):
    return np.array([[i, 0.0, 0.0, 0.0] for i in range(len(clip))]), clip
'''


@pytest.fixture
def nodes(tmp_path):
    folder = tmp_path / "plugins"
    folder.mkdir()
    (folder / "clip_nodes.py").write_text(CLIP_NODES)
    shutil.copy(TEMPORAL_MEDIAN, folder / "temporal_median.py")
    shutil.copy(CSV_POINTS, folder / "csv_points.py")
    return folder


@pytest.fixture
def empty_arena_host(tmp_path):
    # Starts empty: the first frame pyrograph writes grows the file the worker has mapped.
    host = Host(tmp_path, arena_size=0)
    host.hello()
    yield host
    host.close()


class Pyrograph:
    """Answers a whole-clip cook's requests as pyrograph does, keeping a log of them."""

    def __init__(self, host, clips, failing=()):
        self.host = host
        self.clips = clips  # {input name: list of frames}
        self.failing = set(failing)  # (clip, index) answered with frame_error
        self.log = []  # ("need", clip, index) and ("emit", port, index) in the order they came
        self.emitted = {}  # {port: [frames]}
        self.offsets = set()

    def cook(self, path, type_name, params=None, arrays=None, cook_id=9, fps=24.0):
        specs, _ = self.host.put(arrays or {})
        clips = {name: {"len": len(frames), "fps": fps} for name, frames in self.clips.items()}
        self.host.send({
            "op": "cook", "id": cook_id, "type": type_name, "file": str(path), "sha256": sha256(path), "frame": None,
            "params": params or {}, "arrays": specs, "clips": clips, "out_offset": OUT_OFFSET,
        })
        return self.serve(cook_id)

    def serve(self, cook_id):
        """Answers requests until the cook's reply, which it returns."""
        while True:
            message = self.host.receive()
            if message["op"] == "need_frame":
                assert message["id"] == cook_id and set(message) == {"op", "id", "clip", "index"}
                self.log.append(("need", message["clip"], message["index"]))
                self.host.send(self.frame(cook_id, message["clip"], message["index"]))
            elif message["op"] == "emit":
                assert message["id"] == cook_id and set(message) == {"op", "id", "port", "index", "array"}
                self.log.append(("emit", message["port"], message["index"]))
                frames = self.emitted.setdefault(message["port"], [])
                assert message["index"] == len(frames), "frames come in order"
                frames.append(self.host.get(message["array"]).copy())
                self.offsets.add(message["array"]["offset"])
                self.host.send({"op": "ack", "id": cook_id})
            else:
                return message

    def frame(self, cook_id, name, index):
        if (name, index) in self.failing:
            return {"op": "frame_error", "id": cook_id, "message": f"node 'upstream': frame {index}: it broke"}
        # At out_offset, where the worker writes emitted frames too: each side copies a frame out
        # before the other writes the next, and the cook's inputs before out_offset stay intact.
        frame = np.ascontiguousarray(self.clips[name][index], np.float32)
        os.pwrite(self.host.arena, frame.tobytes(), OUT_OFFSET)
        return {"op": "frame", "id": cook_id, "array": {"offset": OUT_OFFSET, "shape": list(frame.shape), "dtype": "<f4"}}


def random_clip(length, shape, seed=1):
    rng = np.random.default_rng(seed)
    return [rng.random(shape, dtype=np.float32) for _ in range(length)]


@pytest.mark.parametrize("shape", [(6, 7), (5, 4, 4)], ids=["gray", "rgba"])
def test_temporal_median_through_the_worker_equals_numpy(empty_arena_host, nodes, shape):
    frames = random_clip(11, shape)
    fake = Pyrograph(empty_arena_host, {"clip": frames})
    reply = fake.cook(nodes / "temporal_median.py", "studio.temporal_median", {"radius": 2}, fps=30.0)
    assert reply["op"] == "result" and reply["id"] == 9, reply
    assert reply["outputs"] == [{"port": "clip", "frames": 11}]
    assert fake.offsets == {OUT_OFFSET}, "every frame is written at out_offset"
    stack = np.stack(frames)
    for i, got in enumerate(fake.emitted["clip"]):
        want = np.median(stack[max(0, i - 2):i + 3], axis=0)
        assert got.dtype == np.float32 and got.shape == shape
        np.testing.assert_array_equal(got, want)
    needs = [index for op, _, index in fake.log if op == "need"]
    assert max(needs.count(i) for i in range(11)) <= 5, "no frame fetched more than 2·radius+1 times"
    assert sorted(needs) == list(range(11)), "in fact each is fetched once"
    # Lazily: frame k is emitted before frame k+3, which only the window of frame k+1 needs, is fetched.
    expected = [("need", "clip", i) for i in range(3)]
    for k in range(11):
        expected += [("emit", "clip", k)] + ([("need", "clip", k + 3)] if k + 3 < 11 else [])
    assert fake.log == expected


def test_a_generator_is_consumed_one_frame_at_a_time(host, nodes):
    frames = random_clip(3, (2, 3))
    fake = Pyrograph(host, {"clip": frames})
    reply = fake.cook(nodes / "clip_nodes.py", "test.double", {"gain": 3.0})
    assert reply["outputs"] == [{"port": "clip", "frames": 3}], reply
    assert fake.log == [("need", "clip", 0), ("emit", "clip", 0), ("need", "clip", 1), ("emit", "clip", 1),
                        ("need", "clip", 2), ("emit", "clip", 2)]
    for got, frame in zip(fake.emitted["clip"], frames):
        np.testing.assert_array_equal(got, frame * np.float32(3.0))


def test_an_exception_in_the_generator_after_two_frames_points_at_the_plugin(host, nodes):
    path = nodes / "clip_nodes.py"
    fake = Pyrograph(host, {"clip": random_clip(5, (2, 2))})
    reply = fake.cook(path, "test.raises_at_2")
    assert reply["op"] == "error" and reply["kind"] == "exception" and reply["port"] is None, reply
    assert (reply["exception"], reply["message"]) == ("ValueError", "frame 2 is cursed")
    assert reply["frames"] == [{"file": str(path), "line": line_of(path, 'raise ValueError("frame 2'), "function": "raises_at_2",
                                "code": 'raise ValueError("frame 2 is cursed")'}]
    assert len(fake.emitted["clip"]) == 2
    assert [entry for entry in fake.log if entry[0] == "need"] == [("need", "clip", i) for i in range(3)]


def test_a_frame_pyrograph_cannot_make_is_a_frame_error(host, nodes):
    fake = Pyrograph(host, {"clip": random_clip(4, (2, 2))}, failing=[("clip", 1)])
    reply = fake.cook(nodes / "clip_nodes.py", "test.double")
    assert reply == {"op": "error", "id": 9, "kind": "frame_error", "port": None, "exception": "FrameError",
                     "message": "node 'upstream': frame 1: it broke", "frames": []}
    assert len(fake.emitted["clip"]) == 1
    # A plugin may catch it and go on; one that makes its own FrameError gets an ordinary exception.
    fake = Pyrograph(host, {"clip": random_clip(4, (2, 2))}, failing=[("clip", 1), ("clip", 2)])
    reply = fake.cook(nodes / "clip_nodes.py", "test.catches_frame_errors")
    assert reply["outputs"] == [{"port": "clip", "frames": 2}], reply
    reply = Pyrograph(host, {"clip": random_clip(1, (2, 2))}).cook(nodes / "clip_nodes.py", "test.own_frame_error")
    assert (reply["kind"], reply["exception"], reply["message"]) == ("exception", "FrameError", "made up")
    assert reply["frames"], "with the plugin's line"


def test_a_negative_index_counts_from_the_end(host, nodes):
    frames = random_clip(6, (3, 2, 4))
    fake = Pyrograph(host, {"clip": frames})
    reply = fake.cook(nodes / "clip_nodes.py", "test.last", fps=12.5)
    assert fake.log == [("need", "clip", 5)]
    image, count, fps = reply["outputs"]
    np.testing.assert_array_equal(host.get(image["array"]), frames[5])
    assert image["array"]["offset"] == OUT_OFFSET
    assert (count, fps) == ({"port": "count", "value": 6}, {"port": "fps", "value": 12.5})
    reply = Pyrograph(host, {"clip": frames}).cook(nodes / "clip_nodes.py", "test.out_of_range")
    assert (reply["kind"], reply["exception"]) == ("exception", "IndexError")
    assert reply["message"] == "frame 6 is outside the clip of 6 frames"


WRONG_CLIPS = {
    "no_frames": ("test.no_frames", "output 'clip': the clip has no frames"),
    "changing_shape": ("test.changing_shape", "output 'clip': frame 3: expected the shape of frame 0, (4, 5), got (4, 6)"),
    "float64_frame": ("test.float64_frame", "output 'clip': frame 1: expected a float32 array of shape (H,W) or (H,W,4), "
                                            "got float64 (2, 2); convert with .astype(np.float32)"),
}


@pytest.mark.parametrize("case", WRONG_CLIPS.values(), ids=WRONG_CLIPS.keys())
def test_a_wrong_clip_is_a_port_error(host, nodes, case):
    type_name, message = case
    reply = Pyrograph(host, {"clip": random_clip(2, (2, 2))}).cook(nodes / "clip_nodes.py", type_name)
    assert reply == {"op": "error", "id": 9, "kind": "port", "port": "clip", "exception": None, "message": message,
                     "frames": []}
    # The worker goes on serving.
    assert Pyrograph(host, {"clip": random_clip(2, (2, 2))}).cook(nodes / "clip_nodes.py", "test.double")["op"] == "result"


def test_several_outputs_emit_clips_in_order_then_write_the_rest(host, nodes):
    frames = random_clip(3, (2, 3))
    still = np.linspace(0, 1, 6, dtype=np.float32).reshape(2, 3)
    fake = Pyrograph(host, {"clip": frames})
    reply = fake.cook(nodes / "clip_nodes.py", "test.several", {"threshold": 0.5}, {"still": still})
    assert reply["op"] == "result", reply
    bright, matte, count, stack = reply["outputs"]
    assert bright == {"port": "bright", "frames": 3} and stack == {"port": "stack", "frames": 3}
    assert count == {"port": "count", "value": 3}
    assert matte["port"] == "matte" and matte["array"] == {"offset": OUT_OFFSET, "shape": [2, 3], "dtype": "|u1"}
    np.testing.assert_array_equal(host.get(matte["array"]), np.where(still > 0.5, 255, 0))
    assert [entry[1] for entry in fake.log if entry[0] == "emit"] == ["bright"] * 3 + ["stack"] * 3
    for i in range(3):
        np.testing.assert_array_equal(fake.emitted["bright"][i], frames[i] + still)
        np.testing.assert_array_equal(fake.emitted["stack"][i], frames[2 - i])


def test_a_clip_input_can_be_returned_as_it_is_with_points_beside_it(host, nodes):
    frames = random_clip(2, (2, 2))
    fake = Pyrograph(host, {"clip": frames})
    reply = fake.cook(nodes / "clip_nodes.py", "test.clip_and_points")
    points, clip = reply["outputs"]
    assert clip == {"port": "clip", "frames": 2} and points["array"]["dtype"] == "<f8"
    np.testing.assert_array_equal(host.get(points["array"]), [[0, 0, 0, 0], [1, 0, 0, 0]])
    for got, frame in zip(fake.emitted["clip"], frames):
        np.testing.assert_array_equal(got, frame)


def test_points_are_written_as_float64(host, nodes):
    reply = Pyrograph(host, {}).cook(nodes / "clip_nodes.py", "test.points", {"which": 0})
    (points,) = reply["outputs"]
    assert points["port"] == "points" and points["array"]["dtype"] == "<f8" and points["array"]["shape"] == [2, 3]
    assert points["array"]["offset"] == OUT_OFFSET
    np.testing.assert_array_equal(host.get(points["array"]), [[0, 1, 2], [3, 4, 5]])
    (points,) = Pyrograph(host, {}).cook(nodes / "clip_nodes.py", "test.points", {"which": 1})["outputs"]
    np.testing.assert_array_equal(host.get(points["array"]), [[0.5, 1, 2, 3]])


WRONG_POINTS = {
    "two_columns": (2, "expected an (N,3) or (N,4) array of finite numbers, got float64 (5, 2)"),
    "nan": (3, "expected an (N,3) or (N,4) array of finite numbers, got float64 (1, 3) with [0.0, 1.0, nan] in row 0"),
    "list": (4, "expected an (N,3) or (N,4) array of finite numbers, got list"),
    "empty": (5, "got float64 (0, 3), which has no points"),
    "negative_seconds": (6, "row 1: the time (column 0, seconds) must be ≥ 0, got -1.0"),
    "bool": (7, "got bool (2, 3)"),
}


@pytest.mark.parametrize("case", WRONG_POINTS.values(), ids=WRONG_POINTS.keys())
def test_wrong_points_are_a_port_error(host, nodes, case):
    which, words = case
    reply = Pyrograph(host, {}).cook(nodes / "clip_nodes.py", "test.points", {"which": which})
    assert reply["op"] == "error" and reply["kind"] == "port" and reply["port"] == "points", reply
    assert reply["message"].startswith("output 'points': ") and words in reply["message"]


def test_csv_points_through_the_worker(host, nodes):
    reply = Pyrograph(host, {}).cook(nodes / "csv_points.py", "studio.csv_points",
                                     {"path": str(EMITTERS), "scale": 2, "offset": [0, 1, 0]})
    (points,) = reply["outputs"]
    assert points["port"] == "points" and points["array"]["dtype"] == "<f8" and points["array"]["shape"] == [12, 4]
    direct = load_module(CSV_POINTS).csv_points(str(EMITTERS), scale=2.0, offset=(0.0, 1.0, 0.0))
    np.testing.assert_array_equal(host.get(points["array"]), direct)
    bad = nodes / "bad.csv"
    bad.write_text("x,y\n1,2\n")
    reply = Pyrograph(host, {}).cook(nodes / "csv_points.py", "studio.csv_points", {"path": str(bad)})
    assert reply["kind"] == "exception" and reply["exception"] == "ValueError" and f"{bad}: no column 'z'" in reply["message"]


def test_a_fetched_frame_is_read_only(host, nodes):
    reply = Pyrograph(host, {"clip": random_clip(1, (2, 2))}).cook(nodes / "clip_nodes.py", "test.writes_frame")
    assert reply["kind"] == "exception" and reply["exception"] == "ValueError" and "read-only" in reply["message"]


def test_a_kept_view_cannot_fetch_after_its_cook(host, nodes):
    path = nodes / "clip_nodes.py"
    assert Pyrograph(host, {"clip": random_clip(2, (2, 2))}).cook(path, "test.keeps_view")["op"] == "result"
    fake = Pyrograph(host, {})
    reply = fake.cook(path, "test.uses_kept_view")
    assert reply["kind"] == "exception" and reply["exception"] == "RuntimeError" and "has finished" in reply["message"]
    assert fake.log == []


def test_sigint_while_waiting_for_a_frame_cancels_and_a_late_frame_is_dropped(host, nodes):
    path = nodes / "clip_nodes.py"
    frames = random_clip(3, (2, 2))
    host.send({"op": "cook", "id": 4, "type": "test.double", "file": str(path), "sha256": sha256(path), "frame": None,
               "params": {}, "arrays": {}, "clips": {"clip": {"len": 3, "fps": 24}}, "out_offset": OUT_OFFSET})
    fake = Pyrograph(host, {"clip": frames})
    assert host.receive() == {"op": "need_frame", "id": 4, "clip": "clip", "index": 0}
    time.sleep(0.1)  # the worker is now reading the reply
    host.process.send_signal(signal.SIGINT)
    reply = host.receive()
    assert reply["op"] == "error" and reply["id"] == 4 and reply["kind"] == "cancelled", reply
    host.send(fake.frame(4, "clip", 0))  # pyrograph answered before it read the cancel
    assert fake.cook(path, "test.double")["outputs"] == [{"port": "clip", "frames": 3}]


def test_sigint_mid_message_keeps_the_stream_in_step(host, nodes):
    path = nodes / "clip_nodes.py"
    frames = random_clip(2, (2, 2))
    fake = Pyrograph(host, {"clip": frames})
    host.send({"op": "cook", "id": 4, "type": "test.last", "file": str(path), "sha256": sha256(path), "frame": None,
               "params": {}, "arrays": {}, "clips": {"clip": {"len": 2, "fps": 24}}, "out_offset": OUT_OFFSET})
    assert host.receive()["op"] == "need_frame"
    answer = fake.frame(4, "clip", 1)
    body = json.dumps(answer).encode()
    data = struct.pack("<I", len(body)) + body
    host.send_bytes(data[:7])  # half a message, then the interrupt, then the rest
    time.sleep(0.1)
    host.process.send_signal(signal.SIGINT)
    assert host.receive()["kind"] == "cancelled"
    host.send_bytes(data[7:])
    assert fake.cook(path, "test.double")["op"] == "result"


def test_sigint_between_cooks_is_still_ignored(host, nodes):
    host.process.send_signal(signal.SIGINT)
    assert Pyrograph(host, {"clip": random_clip(1, (2, 2))}).cook(nodes / "clip_nodes.py", "test.double")["op"] == "result"


def cook_then_answer(host, path, type_name, answer, clips=None):
    """Starts a cook of a clip of 3 frames and answers its first request with `answer`."""
    host.send({"op": "cook", "id": 4, "type": type_name, "file": str(path), "sha256": sha256(path), "frame": None,
               "params": {}, "arrays": {}, "clips": {"clip": {"len": 3, "fps": 24}} if clips is None else clips,
               "out_offset": OUT_OFFSET})
    assert host.receive()["op"] == "need_frame"
    host.send(answer)
    return host.receive()


FATAL_ANSWERS = {
    "another_op": ({"op": "cook", "id": 4}, "waiting for frame or frame_error for cook 4"),
    "another_id": ({"op": "frame", "id": 5, "array": {"offset": 0, "shape": [2, 2], "dtype": "<f4"}}, "for cook 4"),
    "mask_frame": ({"op": "frame", "id": 4, "array": {"offset": 0, "shape": [2, 2], "dtype": "|u1"}}, "not a float32"),
    "no_array": ({"op": "frame", "id": 4}, "missing field 'array'"),
    "outside": ({"op": "frame", "id": 4, "array": {"offset": 1 << 40, "shape": [2, 2], "dtype": "<f4"}}, "outside"),
}


@pytest.mark.parametrize("node", ["test.double", "test.swallows"])
@pytest.mark.parametrize("case", FATAL_ANSWERS.values(), ids=FATAL_ANSWERS.keys())
def test_a_wrong_answer_is_fatal_even_if_the_plugin_catches_it(host, nodes, case, node):
    answer, words = case
    reply = cook_then_answer(host, nodes / "clip_nodes.py", node, answer)
    assert reply["op"] == "fatal" and words in reply["message"], reply
    assert host.wait() == 2


def test_bye_while_waiting_ends_the_worker_quietly(host, nodes):
    host.send({"op": "cook", "id": 4, "type": "test.swallows", "file": str(nodes / "clip_nodes.py"),
               "sha256": sha256(nodes / "clip_nodes.py"), "frame": None, "params": {}, "arrays": {},
               "clips": {"clip": {"len": 3, "fps": 24}}, "out_offset": 0})
    assert host.receive()["op"] == "need_frame"
    host.send({"op": "bye"})
    assert host.wait() == 0
    assert host.process.stdout.read() == b""


MALFORMED_CLIPS = {
    "missing_clip": ({}, "the required input 'clip' was not given"),
    "unknown_clip": ({"clip": {"len": 1, "fps": 24}, "other": {"len": 1, "fps": 24}}, "has no clip input 'other'"),
    "no_len": ({"clip": {"fps": 24}}, "missing field 'len'"),
    "zero_fps": ({"clip": {"len": 1, "fps": 0}}, "fps must be a positive number"),
    "negative_len": ({"clip": {"len": -1, "fps": 24}}, "must not be negative"),
}


@pytest.mark.parametrize("case", MALFORMED_CLIPS.values(), ids=MALFORMED_CLIPS.keys())
def test_a_malformed_clips_field_is_fatal(host, nodes, case):
    clips, words = case
    path = nodes / "clip_nodes.py"
    reply = host.request({"op": "cook", "id": 4, "type": "test.double", "file": str(path), "sha256": sha256(path),
                          "frame": None, "params": {}, "arrays": {}, "clips": clips, "out_offset": 0})
    assert reply["op"] == "fatal" and words in reply["message"], reply
    assert host.wait() == 2


def test_a_clip_for_a_per_frame_node_is_fatal(host, nodes):
    path = nodes / "csv_points.py"
    reply = host.request({"op": "cook", "id": 4, "type": "studio.csv_points", "file": str(path), "sha256": sha256(path),
                          "frame": None, "params": {"path": str(EMITTERS)}, "arrays": {},
                          "clips": {"path": {"len": 1, "fps": 24}}, "out_offset": 0})
    assert reply["op"] == "fatal" and "has no clip input 'path'" in reply["message"]
    assert host.wait() == 2


def test_the_worker_tells_whole_clip_nodes_apart_when_describing(host, nodes):
    path = nodes / "temporal_median.py"
    (entry,) = host.request({"op": "describe", "files": [{"path": str(path), "sha256": sha256(path)}]})["files"]
    assert entry["error"] is None
    assert entry["nodes"] == [load_module(TEMPORAL_MEDIAN).temporal_median.__pyrograph__.as_dict()]
    assert entry["nodes"][0]["time"] == "whole_clip" and entry["nodes"][0]["inputs"][0]["kind"] == "clip"


def test_the_host_modules_are_not_in_the_plugin_frames(host, nodes):
    # view[i] runs through pyrograph_plugin and both host modules; the traceback shows the plugin only.
    path = nodes / "clip_nodes.py"
    reply = Pyrograph(host, {"clip": random_clip(2, (2, 2))}).cook(path, "test.out_of_range")
    assert [frame["file"] for frame in reply["frames"]] == [str(path)]
