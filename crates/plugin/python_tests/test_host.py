"""The plugin worker (pyrograph_host.py) as pyrograph runs it: a subprocess speaking protocol v1
over its stdin/stdout, with images in a shared arena file."""

import hashlib
import importlib.util
import json
import os
import pathlib
import resource
import select
import shutil
import signal
import struct
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
HOST_DIR = ROOT / "crates" / "plugin" / "host"
HOST = HOST_DIR / "pyrograph_host.py"
HEAT_HAZE = ROOT / "examples" / "plugins" / "heat_haze" / "plugins" / "heat_haze.py"
TIMEOUT = 60

# Nodes that misbehave in every way the worker must report; line numbers are found by text.
TEST_NODES = '''
import sys
import time

import numpy as np
from pyrograph_plugin import node, current_frame, Bool, Color, Float, Image, Int, Mask, Outputs, String


def divide(x):
    return x / 0


@node("test.raises", doc="Raises in a helper.")
def raises(image: Image) -> Image:
    return divide(1)


@node("test.float64", doc="Returns float64.")
def float64(image: Image) -> Image:
    return image.astype(np.float64)


@node("test.three_channels", doc="Returns (H,W,3).")
def three_channels(image: Image) -> Image:
    return np.zeros(image.shape[:2] + (3,), np.float32)


@node("test.list", doc="Returns a list.")
def a_list(image: Image) -> Image:
    return [1.0, 2.0]


@node("test.missing_key", doc="Forgets the mask.")
def missing_key(image: Image) -> Outputs(image=Image, mask=Mask):
    return {"image": image}


@node("test.prints", doc="Prints, then returns its input.")
def prints(image: Image, words: String = "hello from the plugin") -> Image:
    print(words)
    sys.stdout.flush()
    return image


@node("test.big", doc="A constant frame.")
def big(size: Int = 100, level: Float = 0.5) -> Image:
    return np.full((size, size, 4), level, np.float32)


@node("test.several", doc="Splits a frame.")
def several(image: Image, mask: Mask, tint: Color = (1, 1, 1, 1), gain: Float = 1.0, keep: Bool = True) -> Outputs(
    gray=Image(channels="gray"), matte=Mask, tint_sum=Float, keep=Bool, count=Int
):
    # Colours arrive as tuples of floats, and a Float as a float even when JSON wrote an int.
    assert isinstance(tint, tuple) and all(isinstance(c, float) for c in tint) and isinstance(gain, float)
    return (image[..., 0].copy(), image[..., 3] > 0.5, sum(tint), keep, np.int64(mask.sum()))


@node("test.writes_input", doc="Tries to edit its input.")
def writes_input(image: Image) -> Image:
    image[0, 0] = 1.0
    return image


@node("test.frame", doc="The frame.")
def frame() -> Float:
    return current_frame()


@node("test.sleeps", doc="Waits to be cancelled.")
def sleeps(marker: String) -> Float:
    open(marker, "w").close()
    while True:
        time.sleep(0.01)
'''

BROKEN = '''from pyrograph_plugin import node

x = 1
if x = 2:
    pass
'''


def sha256(path):
    return hashlib.sha256(pathlib.Path(path).read_bytes()).hexdigest()


def line_of(path, text):
    return next(i for i, line in enumerate(pathlib.Path(path).read_text().splitlines(), 1) if text in line)


def load_module(path):
    sys.path.insert(0, str(HOST_DIR))
    spec = importlib.util.spec_from_file_location(f"direct_{pathlib.Path(path).stem}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


class Host:
    """A running worker and the arena it shares with the test, which plays pyrograph."""

    def __init__(self, tmp_path, arena_size=1 << 16, env=None, max_file_size=None):
        self.stderr_path = tmp_path / "host-stderr.txt"
        self.arena_path = tmp_path / "arena"
        self.arena = os.open(self.arena_path, os.O_RDWR | os.O_CREAT, 0o600)
        os.ftruncate(self.arena, arena_size)
        # A file, not a pipe, for stderr: nothing has to drain it while the worker runs.
        with open(self.stderr_path, "wb") as stderr:
            self.process = subprocess.Popen(
                [sys.executable, "-u", str(HOST)], stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=stderr,
                env={**os.environ, "PYTHONPATH": str(HOST_DIR), **(env or {})},
                preexec_fn=max_file_size and (lambda: resource.setrlimit(resource.RLIMIT_FSIZE, (max_file_size,) * 2)),
            )

    def send_bytes(self, data):
        self.process.stdin.write(data)
        self.process.stdin.flush()

    def send(self, message):
        body = json.dumps(message).encode()
        self.send_bytes(struct.pack("<I", len(body)) + body)

    def _read(self, count):
        data = b""
        fd = self.process.stdout.fileno()
        deadline = time.monotonic() + TIMEOUT
        while len(data) < count:
            ready, _, _ = select.select([fd], [], [], max(0.0, deadline - time.monotonic()))
            assert ready, f"no reply within {TIMEOUT} s; stderr: {self.stderr()}"
            chunk = os.read(fd, count - len(data))
            assert chunk, f"the worker closed its output; stderr: {self.stderr()}"
            data += chunk
        return data

    def receive(self):
        (length,) = struct.unpack("<I", self._read(4))
        return json.loads(self._read(length))

    def request(self, message):
        self.send(message)
        return self.receive()

    def hello(self):
        ready = self.request({"op": "hello", "protocol": 1, "arena": str(self.arena_path)})
        assert ready["op"] == "ready", ready
        os.unlink(self.arena_path)  # as pyrograph does: from now on only the open files reach it
        return ready

    def put(self, arrays):
        """Writes input arrays into the arena, each 64-byte aligned; their specs and where they end."""
        specs, offset = {}, 0
        for name, array in arrays.items():
            os.pwrite(self.arena, np.ascontiguousarray(array).tobytes(), offset)
            specs[name] = {"offset": offset, "shape": list(array.shape), "dtype": array.dtype.str}
            offset += -(-array.nbytes // 64) * 64
        return specs, offset

    def get(self, spec):
        dtype = np.dtype(spec["dtype"])
        size = int(np.prod(spec["shape"])) * dtype.itemsize
        return np.frombuffer(os.pread(self.arena, size, spec["offset"]), dtype).reshape(spec["shape"])

    def stderr(self):
        return self.stderr_path.read_text(errors="replace")

    def wait(self):
        return self.process.wait(timeout=TIMEOUT)

    def close(self):
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait()
        self.process.stdin.close()
        self.process.stdout.close()
        os.close(self.arena)


@pytest.fixture
def plugins(tmp_path):
    """A plugin folder: the example heat haze, the test nodes and a file with a syntax error."""
    folder = tmp_path / "plugins"
    folder.mkdir()
    shutil.copy(HEAT_HAZE, folder / "heat_haze.py")
    (folder / "test_nodes.py").write_text(TEST_NODES)
    (folder / "broken.py").write_text(BROKEN)
    return folder


@pytest.fixture
def host(tmp_path):
    host = Host(tmp_path)
    host.hello()
    yield host
    host.close()


def cook(host, path, type_name, params=None, arrays=None, frame=7, out_offset=None):
    specs, end = host.put(arrays or {})
    return host.request({
        "op": "cook", "id": 42, "type": type_name, "file": str(path), "sha256": sha256(path), "frame": frame,
        "params": params or {}, "arrays": specs, "out_offset": end if out_offset is None else out_offset,
    })


def test_hello_and_describe_a_good_and_a_broken_file(tmp_path, plugins):
    host = Host(tmp_path)
    ready = host.hello()
    assert ready == {"op": "ready", "protocol": 1, "python": ".".join(map(str, sys.version_info[:3])),
                     "numpy": np.__version__, "pid": host.process.pid}
    files = [{"path": str(plugins / name), "sha256": sha256(plugins / name)} for name in ("heat_haze.py", "broken.py")]
    described = host.request({"op": "describe", "files": files})
    assert described["op"] == "described"
    good, broken = described["files"]
    expected = load_module(HEAT_HAZE).heat_haze.__pyrograph__.as_dict()
    assert good == dict(files[0], nodes=[expected], error=None)
    assert broken["path"] == files[1]["path"] and broken["nodes"] == []
    assert broken["error"]["exception"] == "SyntaxError"
    assert broken["error"]["frames"] == [{"file": str(plugins / "broken.py"), "line": line_of(plugins / "broken.py", "if x = 2"),
                                          "function": "<module>", "code": "if x = 2:"}]
    host.send({"op": "bye"})
    assert host.wait() == 0
    host.close()


def test_a_changed_file_is_reported_and_a_new_hash_loads_the_new_code(host, plugins):
    path = plugins / "test_nodes.py"
    stale = {"path": str(path), "sha256": "0" * 64}
    (entry,) = host.request({"op": "describe", "files": [stale]})["files"]
    assert entry["nodes"] == [] and "changed while it was being read" in entry["error"]["message"]
    assert cook(host, path, "test.big", {"size": 1, "level": 0.5})["op"] == "result"
    path.write_text(TEST_NODES.replace('@node("test.big"', '@node("test.huge"'))
    reply = cook(host, path, "test.big", {"size": 1})
    assert reply["kind"] == "load" and "test.huge" in reply["message"]


def test_a_type_declared_twice_in_a_file_is_a_load_error(host, plugins):
    path = plugins / "twice.py"
    path.write_text(TEST_NODES.replace('@node("test.list"', '@node("test.float64"'))
    (entry,) = host.request({"op": "describe", "files": [{"path": str(path), "sha256": sha256(path)}]})["files"]
    assert entry["nodes"] == [] and entry["error"]["exception"] is None
    assert entry["error"]["message"] == (f"test.float64 is declared twice: by float64 (line {line_of(path, 'def float64(')}) "
                                         f"and a_list (line {line_of(path, 'def a_list(')})")


def test_a_plugin_imports_helpers_from_its_folder(host, plugins):
    (plugins / "_shared.py").write_text("GAIN = 3.5\n")
    path = plugins / "uses_helper.py"
    path.write_text("from _shared import GAIN\nfrom pyrograph_plugin import node, Float\n\n"
                    "@node('test.gain', doc='The shared gain.')\ndef gain() -> Float:\n    return GAIN\n")
    assert cook(host, path, "test.gain")["outputs"] == [{"port": "value", "value": 3.5}]


@pytest.mark.parametrize("shape", [(37, 53, 4), (29, 41)], ids=["rgba", "gray"])
@pytest.mark.parametrize("axis", ["vertical", "horizontal"])
def test_cooking_heat_haze_equals_calling_it(host, plugins, shape, axis):
    image = np.random.default_rng(7).random(shape, dtype=np.float32) * 4 - 1
    params = {"amount": 3.7, "wavelength": 11, "axis": axis}
    reply = cook(host, plugins / "heat_haze.py", "studio.heat_haze", params, {"image": image}, out_offset=image.nbytes + 3)
    assert reply["op"] == "result" and reply["id"] == 42 and reply["ms"] >= 0, reply
    (output,) = reply["outputs"]
    assert output["port"] == "image" and output["array"]["dtype"] == "<f4"
    assert output["array"]["offset"] >= image.nbytes + 3 and output["array"]["offset"] % 64 == 0
    direct = load_module(HEAT_HAZE).heat_haze(image.copy(), amount=3.7, wavelength=11.0, axis=axis)
    assert not np.array_equal(direct, image)
    np.testing.assert_array_equal(host.get(output["array"]), direct)


def test_an_exception_points_at_the_plugin_lines(host, plugins):
    path = plugins / "test_nodes.py"
    reply = cook(host, path, "test.raises", arrays={"image": np.zeros((2, 2), np.float32)})
    assert reply["op"] == "error" and reply["id"] == 42 and reply["kind"] == "exception" and reply["port"] is None
    assert reply["exception"] == "ZeroDivisionError" and reply["message"] == "division by zero"
    assert reply["frames"] == [
        {"file": str(path), "line": line_of(path, "return divide(1)"), "function": "raises", "code": "return divide(1)"},
        {"file": str(path), "line": line_of(path, "return x / 0"), "function": "divide", "code": "return x / 0"},
    ]


def test_a_read_only_input_cannot_be_edited(host, plugins):
    reply = cook(host, plugins / "test_nodes.py", "test.writes_input", arrays={"image": np.zeros((2, 2), np.float32)})
    assert reply["kind"] == "exception" and reply["exception"] == "ValueError" and "read-only" in reply["message"]


WRONG_RETURNS = {
    "float64": ("test.float64", "image", "got float64 (3, 5, 4); convert with .astype(np.float32)"),
    "three_channels": ("test.three_channels", "image", "shape (H,W) or (H,W,4), got float32 (3, 5, 3)"),
    "list": ("test.list", "image", "expected a float32 array of shape (H,W) or (H,W,4), got list"),
    "missing_key": ("test.missing_key", "mask", "missing from the returned dict"),
}


@pytest.mark.parametrize("case", WRONG_RETURNS.values(), ids=WRONG_RETURNS.keys())
def test_a_wrong_return_names_the_output(host, plugins, case):
    type_name, port, words = case
    reply = cook(host, plugins / "test_nodes.py", type_name, arrays={"image": np.zeros((3, 5, 4), np.float32)})
    assert reply["op"] == "error" and reply["kind"] == "port", reply
    assert reply["port"] == port and reply["exception"] is None and reply["frames"] == []
    assert reply["message"].startswith(f"output '{port}': ") and words in reply["message"]


def test_several_outputs_are_checked_and_written_in_declared_order(host, plugins):
    image = np.random.default_rng(3).random((4, 6, 4), dtype=np.float32)
    mask = np.zeros((4, 6), np.uint8)
    mask[1:3] = 2
    params = {"tint": [1, 0.5, 0.25, 1], "gain": 2, "keep": False}
    reply = cook(host, plugins / "test_nodes.py", "test.several", params, {"image": image, "mask": mask}, out_offset=100)
    assert reply["op"] == "result", reply
    gray, matte, tint_sum, keep, total = reply["outputs"]
    assert [o["port"] for o in reply["outputs"]] == ["gray", "matte", "tint_sum", "keep", "count"]
    assert gray["array"]["offset"] == 128 and matte["array"]["offset"] == 256  # 64-aligned after 100, then after 96 bytes
    np.testing.assert_array_equal(host.get(gray["array"]), image[..., 0])
    assert matte["array"]["dtype"] == "|u1"
    np.testing.assert_array_equal(host.get(matte["array"]), np.where(image[..., 3] > 0.5, 255, 0))
    assert tint_sum == {"port": "tint_sum", "value": 2.75} and keep == {"port": "keep", "value": False}
    assert total == {"port": "count", "value": 24}


def test_the_frame_reaches_the_plugin(host, plugins):
    assert cook(host, plugins / "test_nodes.py", "test.frame", frame=12)["outputs"] == [{"port": "value", "value": 12.0}]
    reply = cook(host, plugins / "test_nodes.py", "test.frame", frame=None)
    assert reply["kind"] == "port" and reply["port"] == "value" and "got NoneType" in reply["message"]


def test_print_goes_to_stderr_not_into_the_protocol(tmp_path, plugins):
    host = Host(tmp_path)
    host.hello()
    image = np.ones((2, 3), np.float32)
    reply = cook(host, plugins / "test_nodes.py", "test.prints", {"words": "a line with no frame"}, {"image": image})
    assert reply["op"] == "result"
    np.testing.assert_array_equal(host.get(reply["outputs"][0]["array"]), image)
    host.send({"op": "bye"})
    assert host.wait() == 0
    assert "a line with no frame" in host.stderr()
    host.close()


def test_an_output_larger_than_the_arena_grows_it(tmp_path, plugins):
    host = Host(tmp_path, arena_size=0)  # an empty file cannot even be mapped
    host.hello()
    reply = cook(host, plugins / "test_nodes.py", "test.big", {"size": 100, "level": 0.25}, out_offset=1000)
    (output,) = reply["outputs"]
    assert output["array"] == {"offset": 1024, "shape": [100, 100, 4], "dtype": "<f4"}
    assert os.fstat(host.arena).st_size >= 1024 + 160000
    np.testing.assert_array_equal(host.get(output["array"]), np.full((100, 100, 4), 0.25, np.float32))
    # pyrograph may grow the file too: a later cook sees inputs past the old end.
    os.ftruncate(host.arena, 400000)
    image = np.full((8, 8), 3.0, np.float32)
    os.pwrite(host.arena, image.tobytes(), 300032)
    reply = host.request({
        "op": "cook", "id": 43, "type": "test.prints", "file": str(plugins / "test_nodes.py"),
        "sha256": sha256(plugins / "test_nodes.py"), "frame": None, "params": {},
        "arrays": {"image": {"offset": 300032, "shape": [8, 8], "dtype": "<f4"}}, "out_offset": 0,
    })
    assert reply["op"] == "result", reply
    np.testing.assert_array_equal(host.get(reply["outputs"][0]["array"]), image)
    host.close()


def test_an_arena_that_cannot_grow_fails_the_cook_not_the_worker(tmp_path, plugins):
    host = Host(tmp_path, arena_size=0, max_file_size=1 << 20)  # Python ignores SIGXFSZ: growing raises
    host.hello()
    reply = cook(host, plugins / "test_nodes.py", "test.big", {"size": 1000})
    assert reply["kind"] == "exception" and "could not write the outputs into the shared file" in reply["message"]
    assert cook(host, plugins / "test_nodes.py", "test.big", {"size": 10})["op"] == "result"
    host.close()


def test_a_load_error_and_an_unknown_type_fail_the_cook(host, plugins):
    reply = cook(host, plugins / "broken.py", "test.anything")
    assert reply["kind"] == "load" and reply["exception"] == "SyntaxError"
    assert reply["frames"][-1]["line"] == line_of(plugins / "broken.py", "if x = 2")
    reply = cook(host, plugins / "heat_haze.py", "studio.heat_wave")
    assert reply["kind"] == "load" and "does not declare studio.heat_wave (it declares studio.heat_haze)" in reply["message"]


def test_sigint_cancels_the_running_cook_only(host, plugins, tmp_path):
    marker = tmp_path / "started"
    path = plugins / "test_nodes.py"
    host.send({"op": "cook", "id": 5, "type": "test.sleeps", "file": str(path), "sha256": sha256(path),
               "frame": None, "params": {"marker": str(marker)}, "arrays": {}, "out_offset": 0})
    deadline = time.monotonic() + TIMEOUT
    while not marker.exists():
        assert time.monotonic() < deadline
        time.sleep(0.01)
    host.process.send_signal(signal.SIGINT)
    reply = host.receive()
    assert reply["op"] == "error" and reply["id"] == 5 and reply["kind"] == "cancelled"
    host.process.send_signal(signal.SIGINT)  # between cooks: ignored
    assert cook(host, path, "test.big", {"size": 1})["op"] == "result"


MALFORMED = {
    "not_json": b"{op: cook",
    "not_an_object": b"[1, 2]",
    "unknown_op": b'{"op": "render"}',
    "missing_field": b'{"op": "cook", "type": "test.big"}',
    "wrong_type": b'{"op": "describe", "files": "heat_haze.py"}',
}


@pytest.mark.parametrize("body", MALFORMED.values(), ids=MALFORMED.keys())
def test_a_malformed_request_is_fatal(host, body):
    host.send_bytes(struct.pack("<I", len(body)) + body)
    reply = host.receive()
    assert reply["op"] == "fatal" and reply["message"]
    assert host.wait() == 2


def test_an_oversized_frame_is_fatal(host):
    host.send_bytes(struct.pack("<I", (16 << 20) + 1))
    assert "limit" in host.receive()["message"]
    assert host.wait() == 2


def test_an_undeclared_input_is_fatal(host, plugins):
    reply = cook(host, plugins / "heat_haze.py", "studio.heat_haze", {"amount": 1.0, "speed": 2.0},
                 {"image": np.zeros((2, 2), np.float32)})
    assert reply["op"] == "fatal" and "speed" in reply["message"]
    assert host.wait() == 2


def test_end_of_input_exits_quietly(tmp_path):
    host = Host(tmp_path)
    host.hello()
    host.process.stdin.close()
    assert host.wait() == 0
    assert host.process.stdout.read() == b""
    host.close()


def test_another_protocol_is_fatal(tmp_path):
    host = Host(tmp_path)
    reply = host.request({"op": "hello", "protocol": 2, "arena": str(host.arena_path)})
    assert reply["op"] == "fatal" and "protocol 1, not 2" in reply["message"]
    assert host.wait() == 1
    host.close()


def test_a_python_without_numpy_gets_a_fatal_message(tmp_path):
    fake = tmp_path / "no_numpy" / "numpy"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text("raise ImportError('No module named numpy')\n")
    host = Host(tmp_path, env={"PYTHONPATH": f"{HOST_DIR}{os.pathsep}{fake.parent}"})
    reply = host.request({"op": "hello", "protocol": 1, "arena": str(host.arena_path)})
    assert reply == {"op": "fatal", "message": f"numpy is not installed for {sys.executable} (No module named numpy): "
                                               "install it (pip install numpy) or point PYROGRAPH_PYTHON at a Python that has it"}
    assert host.wait() == 1
    host.close()
