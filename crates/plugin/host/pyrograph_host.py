"""The pyrograph plugin worker: loads plugin files and cooks their nodes for the Rust process.

pyrograph starts it as `python3 -u pyrograph_host.py` with PYTHONPATH set to this folder and speaks
protocol v1 over stdin/stdout: each message is a 4-byte little-endian length and that many bytes
of UTF-8 JSON. Images travel through the arena, a shared file that both sides map; the messages
only carry offsets, shapes and dtypes.

Exit status: 0 after `bye` or when pyrograph closes the pipe, 1 when this Python cannot serve
(no numpy, another protocol, no arena), 2 after a malformed request. Both failures first send
`{"op": "fatal", "message": ...}`.
"""

import contextlib
import hashlib
import io
import json
import linecache
import mmap
import os
import platform
import signal
import struct
import sys
import time
import tokenize
import traceback
import types

import pyrograph_plugin

PROTOCOL = 1
MAX_FRAME = 16 << 20
ALIGN = 64  # output arrays start on cache-line boundaries
FRAMES_KEPT = 5
TEXT_KEPT = 8000  # longest message or code line sent, so a plugin's huge message cannot burst a frame
DTYPES = ("<f4", "|u1")  # float32 images, uint8 masks
VECTOR_SIZES = {"color": 4, "vec2": 2, "vec3": 3}

np = None  # numpy, imported on hello so a missing numpy becomes a clear fatal message


class Stop(Exception):
    """Ends the worker with an exit status, after sending `fatal` when there is a message."""

    def __init__(self, status, message=None):
        super().__init__(message)
        self.status = status
        self.message = message


class Malformed(Stop):
    """A request this worker cannot have been sent by a correct pyrograph: the worker is broken."""

    def __init__(self, message):
        super().__init__(2, message)


class LoadError(Exception):
    """A plugin file failed to load; `error` is the {exception, message, frames} sent back."""

    def __init__(self, error):
        super().__init__(error["message"])
        self.error = error


class PortError(Exception):
    """A returned value does not match the declared outputs; `port` is the output at fault or None."""

    def __init__(self, port, message):
        super().__init__(message)
        self.port = port


# ---------------------------------------------------------------------------------------------
# Framing.


class Channel:
    """The protocol's private pipe ends, out of reach of a plugin's print() and input()."""

    def __init__(self):
        self.inp = os.dup(0)
        self.out = os.dup(1)
        # fd 1 becomes stderr, so print() in a plugin (or a library it calls) cannot corrupt a
        # frame; fd 0 becomes /dev/null, so input() gets EOF instead of eating requests.
        null = os.open(os.devnull, os.O_RDONLY)
        os.dup2(null, 0)
        os.close(null)
        os.dup2(2, 1)

    def _read(self, count):
        data = b""
        while len(data) < count:
            chunk = os.read(self.inp, count - len(data))
            if not chunk:
                if data:
                    raise Malformed(f"the input ended inside a frame ({len(data)} of {count} bytes)")
                raise Stop(0)
            data += chunk
        return data

    def receive(self) -> dict:
        (length,) = struct.unpack("<I", self._read(4))
        if length > MAX_FRAME:
            raise Malformed(f"a frame of {length} bytes is over the {MAX_FRAME}-byte limit")
        body = self._read(length)
        try:
            message = json.loads(body)
        except ValueError as error:
            raise Malformed(f"a frame is not UTF-8 JSON: {error}") from None
        if not isinstance(message, dict) or not isinstance(message.get("op"), str):
            raise Malformed("a message must be a JSON object with a string \"op\"")
        return message

    def send(self, message):
        # "replace" turns lone surrogates (undecodable file names) into '?' rather than failing.
        body = json.dumps(message, ensure_ascii=False, allow_nan=False).encode("utf-8", "replace")
        data = struct.pack("<I", len(body)) + body
        while data:
            data = data[os.write(self.out, data):]


def field(message, name, kinds, nullable=False):
    """message[name], checked to be of `kinds`; anything else is a malformed request."""
    if not isinstance(message, dict):
        raise Malformed(f"expected a JSON object, got {message!r:.200}")
    if name not in message:
        raise Malformed(f"op {message.get('op', '?')!r}: missing field {name!r}")
    value = message[name]
    if value is None and nullable:
        return None
    if not isinstance(value, kinds) or (isinstance(value, bool) and bool not in kinds):
        raise Malformed(f"field {name!r} has the wrong type: {value!r:.200}")
    return value


def count(message, name):
    """A non-negative integer field (an offset, a size or an id)."""
    value = field(message, name, (int,))
    if value < 0:
        raise Malformed(f"field {name!r} must not be negative, got {value}")
    return value


def clip(text):
    return text if len(text) <= TEXT_KEPT else text[:TEXT_KEPT] + " … (cut)"


# ---------------------------------------------------------------------------------------------
# The arena.


class Arena:
    """The shared file. pyrograph may grow it between cooks, and so may a cook's outputs."""

    def __init__(self, path):
        try:
            self.fd = os.open(path, os.O_RDWR)
        except OSError as error:
            raise Stop(1, f"cannot open the arena {path}: {error}") from None
        self.size = 0
        self.map = None
        self.refresh()

    def refresh(self):
        size = os.fstat(self.fd).st_size
        if size != self.size:
            # The old map is not closed: arrays a plugin kept from an earlier cook still view it.
            self.map = mmap.mmap(self.fd, size) if size else None
            self.size = size

    def view(self, name, spec):
        """A read-only array on an input's bytes, without a copy."""
        offset = count(spec, "offset")
        shape = field(spec, "shape", (list,))
        dtype = field(spec, "dtype", (str,))
        if dtype not in DTYPES or not all(isinstance(n, int) and not isinstance(n, bool) and n >= 0 for n in shape):
            raise Malformed(f"array {name!r}: unsupported dtype or shape: {dtype!r} {shape!r}")
        dtype = np.dtype(dtype)
        nbytes = int(np.prod(shape, dtype=np.int64)) * dtype.itemsize
        if self.map is None or offset + nbytes > self.size:
            raise Malformed(f"array {name!r}: bytes {offset}..{offset + nbytes} lie outside the {self.size}-byte arena")
        array = np.ndarray(shape, dtype, buffer=self.map, offset=offset)
        array.flags.writeable = False
        return array

    def write(self, arrays, start):
        """Writes arrays C-contiguous one after the other from `start`, each 64-byte aligned, growing
        the file when they do not fit; their offsets."""
        offsets = []
        end = start
        for array in arrays:
            offset = -(-end // ALIGN) * ALIGN
            offsets.append(offset)
            end = offset + array.size * stored_dtype(array).itemsize
        self.refresh()
        if end > self.size:
            os.ftruncate(self.fd, end)
            self.refresh()
        for array, offset in zip(arrays, offsets):
            out = np.ndarray(array.shape, stored_dtype(array), buffer=self.map, offset=offset)
            out[...] = array
            if array.dtype == np.bool_:
                out *= 255  # True is 255 in a mask
        return offsets


def stored_dtype(array):
    """The dtype an output array is written as: images stay float32, masks become uint8."""
    return np.dtype(np.float32 if array.dtype == np.float32 else np.uint8)


# ---------------------------------------------------------------------------------------------
# Loading plugin files.


def frames_of(traceback_):
    """The last frames of a traceback outside this worker and the declaration API."""
    ours = {os.path.realpath(__file__), os.path.realpath(pyrograph_plugin.__file__)}
    frames = [f for f in traceback.extract_tb(traceback_) if os.path.realpath(f.filename) not in ours]
    return [
        {"file": f.filename, "line": f.lineno or 0, "function": f.name, "code": clip(f.line or "")}
        for f in frames[-FRAMES_KEPT:]
    ]


def error_of(exception):
    """The {exception, message, frames} form of an exception raised by plugin code."""
    frames = frames_of(exception.__traceback__)
    message = str(exception)
    if isinstance(exception, SyntaxError):
        # The offending line is not on the traceback: it comes from the error itself.
        message = exception.msg
        frames.append({
            "file": exception.filename or "", "line": exception.lineno or 0, "function": "<module>",
            "code": clip((exception.text or "").strip()),
        })
    return {"exception": type(exception).__name__, "message": clip(message), "frames": frames[-FRAMES_KEPT:]}


class Loaded:
    """A plugin file as loaded: its content hash, its module and its node types by name."""

    def __init__(self, sha256, module, nodes):
        self.sha256 = sha256
        self.module = module
        self.nodes = nodes


class Plugins:
    """The loaded plugin files, one version per path: a cook does not execute the file again."""

    def __init__(self):
        self.files = {}

    def load(self, path, sha256) -> Loaded:
        loaded = self.files.get(path)
        if loaded is not None and loaded.sha256 == sha256:
            return loaded
        try:
            with open(path, "rb") as file:
                source = file.read()
        except OSError as error:
            raise LoadError({"exception": type(error).__name__, "message": str(error), "frames": []}) from None
        if hashlib.sha256(source).hexdigest() != sha256.lower():
            raise LoadError({"exception": None, "message": "the file changed while it was being read; try again", "frames": []})
        module, declared = self._execute(path, sha256, source)
        nodes = {}
        for declaration in declared:
            if declaration.type_name in nodes:
                sys.modules.pop(module.__name__, None)
                first = nodes[declaration.type_name]
                raise LoadError({
                    "exception": None,
                    "message": f"{declaration.type_name} is declared twice: by {first.function.__name__} "
                               f"(line {first.line}) and {declaration.function.__name__} (line {declaration.line})",
                    "frames": [],
                })
            nodes[declaration.type_name] = declaration
        if loaded is not None:
            sys.modules.pop(loaded.module.__name__, None)
        self.files[path] = Loaded(sha256, module, nodes)
        return self.files[path]

    @staticmethod
    def _execute(path, sha256, source):
        """Runs the file as a fresh module; the module and the nodes it declared."""
        stem = os.path.splitext(os.path.basename(path))[0]
        module = types.ModuleType(f"pyrograph_plugins.{stem}_{sha256[:12]}")
        module.__file__ = path
        # In sys.modules while it runs, as an imported module is: dataclasses and pickle look there.
        sys.modules[module.__name__] = module
        # Helpers beside the plugin (pyrograph skips `_name.py` files when it looks for plugins)
        # import by name; appended, so a plugin file cannot shadow a module numpy needs.
        folder = os.path.dirname(path)
        if folder not in sys.path:
            sys.path.append(folder)
        pyrograph_plugin.take_declared()
        try:
            code = compile(source, path, "exec", dont_inherit=True)
            remember_source(path, source)
            exec(code, module.__dict__)
        except KeyboardInterrupt:
            sys.modules.pop(module.__name__, None)
            raise
        except BaseException as error:  # SystemExit too: a plugin cannot end the worker
            sys.modules.pop(module.__name__, None)
            raise LoadError(error_of(error)) from None
        finally:
            declared = pyrograph_plugin.take_declared()
        return module, declared


def remember_source(path, source):
    """Puts the loaded text in linecache, so tracebacks show the lines that ran even if the file
    has changed since (mtime None keeps checkcache from dropping the entry)."""
    encoding, _ = tokenize.detect_encoding(io.BytesIO(source).readline)
    lines = source.decode(encoding, "replace").splitlines(keepends=True)
    linecache.cache[path] = (len(source), None, lines, path)


# ---------------------------------------------------------------------------------------------
# Cooking.


# SIGINT cancels the plugin code that is running; between cooks there is nothing to cancel, and
# raising there would end the worker.
_cancellable = False


def on_interrupt(signum, frame):
    if _cancellable:
        raise KeyboardInterrupt


@contextlib.contextmanager
def cancellable():
    """Lets SIGINT raise KeyboardInterrupt in the plugin code run inside."""
    global _cancellable
    try:
        _cancellable = True
        yield
    finally:
        _cancellable = False


def argument(port, value):
    """A parameter's JSON value as the function receives it."""
    kind = port["kind"]
    if kind in VECTOR_SIZES:
        if isinstance(value, list) and len(value) == VECTOR_SIZES[kind] and all(is_number(x) for x in value):
            return tuple(float(x) for x in value)
    elif kind == "float":
        if is_number(value):
            return float(value)
    elif kind == "int":
        if isinstance(value, int) and not isinstance(value, bool):
            return value
    elif kind == "bool":
        if isinstance(value, bool):
            return value
    elif kind in ("string", "enum", "path"):
        if isinstance(value, str):
            return value
    raise Malformed(f"parameter {port['name']!r} ({kind}) cannot be {value!r:.200}")


def is_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def arguments(declaration, params, arrays, arena):
    """The keyword arguments of a cook: parameters from JSON, images and masks from the arena."""
    ports = {port["name"]: port for port in declaration.inputs}
    arena.refresh()  # pyrograph grows the arena when a cook's inputs do not fit
    kwargs = {}
    for names, connection in ((params, False), (arrays, True)):
        for name, value in names.items():
            port = ports.get(name)
            if port is None or (port["kind"] in ("image", "mask")) != connection:
                raise Malformed(f"{declaration.type_name} has no {'array' if connection else 'parameter'} input {name!r}")
            kwargs[name] = arena.view(name, value) if connection else argument(port, value)
    for port in declaration.inputs:
        if port["name"] not in kwargs and port["default"] is None:
            raise Malformed(f"{declaration.type_name}: the required input {port['name']!r} was not given")
    return kwargs


def check_image(port, value):
    channels = port["channels"]
    shapes = {"any": "(H,W) or (H,W,4)", "gray": "(H,W)", "rgba": "(H,W,4)"}[channels]
    expected = f"expected a float32 array of shape {shapes}"
    if not isinstance(value, np.ndarray):
        raise PortError(port["name"], f"{expected}, got {type(value).__name__}")
    shape = value.shape
    fits = (len(shape) == 2 and channels != "rgba") or (len(shape) == 3 and shape[2] == 4 and channels != "gray")
    fits = fits and shape[0] >= 1 and shape[1] >= 1
    if fits and value.dtype == np.float32:
        return value
    hint = "; convert with .astype(np.float32)" if fits else ""
    raise PortError(port["name"], f"{expected}, got {value.dtype} {shape}{hint}")


def check_mask(port, value):
    expected = "expected a uint8 or bool array of shape (H,W)"
    if not isinstance(value, np.ndarray):
        raise PortError(port["name"], f"{expected}, got {type(value).__name__}")
    if value.ndim == 2 and min(value.shape) >= 1 and value.dtype in (np.uint8, np.bool_):
        return value
    raise PortError(port["name"], f"{expected}, got {value.dtype} {value.shape}")


def check_value(port, value):
    """A Float, Int or Bool output as JSON."""
    kind = port["kind"]
    is_bool = isinstance(value, (bool, np.bool_))
    if kind == "float" and isinstance(value, (int, float, np.integer, np.floating)) and not is_bool:
        if np.isfinite(value):
            return float(value)
        raise PortError(port["name"], f"expected a finite float, got {value}")
    if kind == "int" and isinstance(value, (int, np.integer)) and not is_bool:
        if -(1 << 63) <= int(value) < (1 << 63):
            return int(value)
        raise PortError(port["name"], f"expected an int that fits in 64 bits, got {value}")
    if kind == "bool" and is_bool:
        return bool(value)
    expected = {"float": "a float (or an int)", "int": "an int", "bool": "a bool"}[kind]
    raise PortError(port["name"], f"expected {expected}, got {type(value).__name__}")


CHECKS = {"image": check_image, "mask": check_mask, "float": check_value, "int": check_value, "bool": check_value}


def returned_values(declaration, result):
    """The returned value of each declared output, in declaration order."""
    if not declaration.several_outputs:
        return [result]
    names = [port["name"] for port in declaration.outputs]
    wanted = f"a dict with the keys {', '.join(names)} or a tuple of {len(names)} values in that order"
    if isinstance(result, dict):
        missing = [name for name in names if name not in result]
        if missing:
            raise PortError(missing[0], f"missing from the returned dict (it has {list(result)}); expected {wanted}")
        extra = [key for key in result if key not in names]
        if extra:
            raise PortError(None, f"the returned dict has {extra}, which are not outputs; expected {wanted}")
        return [result[name] for name in names]
    if isinstance(result, (tuple, list)):
        if len(result) != len(names):
            raise PortError(None, f"expected {wanted}, got a {type(result).__name__} of {len(result)}")
        return list(result)
    raise PortError(None, f"expected {wanted}, got {type(result).__name__}")


def call(declaration, kwargs, frame):
    """Runs the node function, cancellable; its result and the time it took in ms."""
    started = time.perf_counter()
    try:
        pyrograph_plugin._frame = frame
        with cancellable():
            result = declaration.function(**kwargs)
    finally:
        pyrograph_plugin._frame = None
    return result, (time.perf_counter() - started) * 1000


class Worker:
    """Serves describe and cook once hello has opened the arena."""

    def __init__(self, arena):
        self.arena = arena
        self.plugins = Plugins()

    def describe(self, request):
        files = []
        for entry in field(request, "files", (list,)):
            path = field(entry, "path", (str,))
            sha256 = field(entry, "sha256", (str,))
            try:
                nodes = [d.as_dict() for d in self.plugins.load(path, sha256).nodes.values()]
                error = None
            except LoadError as failure:
                nodes, error = [], failure.error
            files.append({"path": path, "sha256": sha256, "nodes": nodes, "error": error})
        return {"op": "described", "files": files}

    def cook(self, request):
        cook_id = count(request, "id")
        type_name = field(request, "type", (str,))
        path = field(request, "file", (str,))
        sha256 = field(request, "sha256", (str,))
        frame = field(request, "frame", (int,), nullable=True)
        params = field(request, "params", (dict,))
        arrays = field(request, "arrays", (dict,))
        out_offset = count(request, "out_offset")

        def error(kind, port=None, exception=None, message="", frames=()):
            return {"op": "error", "id": cook_id, "kind": kind, "port": port, "exception": exception,
                    "message": message, "frames": list(frames)}

        try:
            with cancellable():  # a slow import at the top of a plugin file can be cancelled too
                loaded = self.plugins.load(path, sha256)
            declaration = loaded.nodes.get(type_name)
            if declaration is None:
                declared = ", ".join(loaded.nodes) or "no node types"
                return error("load", message=f"{path} does not declare {type_name} (it declares {declared})")
            result, ms = call(declaration, arguments(declaration, params, arrays, self.arena), frame)
        except LoadError as failure:
            return error("load", **failure.error)
        except KeyboardInterrupt:
            return error("cancelled", exception="KeyboardInterrupt", message="the cook was cancelled")
        except Stop:
            raise
        except BaseException as exception:  # SystemExit too: a plugin cannot end the worker
            return error("exception", **error_of(exception))
        try:
            outputs = self.outputs(declaration, result, out_offset)
        except PortError as failure:
            text = f"output '{failure.port}': {failure}" if failure.port else str(failure)
            return error("port", port=failure.port, message=text)
        except OSError as failure:  # the arena cannot grow: memory or the file system is full
            text = f"could not write the outputs into the shared file: {failure}"
            return error("exception", exception=type(failure).__name__, message=text)
        return {"op": "result", "id": cook_id, "outputs": outputs, "ms": round(ms, 3)}

    def outputs(self, declaration, result, out_offset):
        """Checks the result against the declared outputs and writes its arrays to the arena."""
        ports = declaration.outputs
        checked = [CHECKS[port["kind"]](port, value) for port, value in zip(ports, returned_values(declaration, result))]
        arrays = [value for value in checked if isinstance(value, np.ndarray)]
        offsets = iter(self.arena.write(arrays, out_offset))
        outputs = []
        for port, value in zip(ports, checked):
            if isinstance(value, np.ndarray):
                dtype = stored_dtype(value).str
                array = {"offset": next(offsets), "shape": list(value.shape), "dtype": dtype}
                outputs.append({"port": port["name"], "array": array})
            else:
                outputs.append({"port": port["name"], "value": value})
        return outputs


# ---------------------------------------------------------------------------------------------
# The session.


def hello(channel, message) -> Worker:
    """Answers hello: imports numpy and opens the arena, or stops with a fatal message."""
    global np
    if message["op"] != "hello":
        raise Malformed(f"the first message must be hello, got {message['op']!r}")
    protocol = field(message, "protocol", (int,))
    if protocol != PROTOCOL:
        raise Stop(1, f"this worker speaks protocol {PROTOCOL}, not {protocol}: its pyrograph_host.py is from another version")
    path = field(message, "arena", (str,))
    try:
        import numpy
    except Exception as error:  # a broken install raises more than ImportError
        raise Stop(1, f"numpy is not installed for {sys.executable} ({error}): install it (pip install numpy) "
                      "or point PYROGRAPH_PYTHON at a Python that has it") from None
    np = numpy
    worker = Worker(Arena(path))
    channel.send({"op": "ready", "protocol": PROTOCOL, "python": platform.python_version(),
                  "numpy": numpy.__version__, "pid": os.getpid()})
    return worker


def serve(channel):
    worker = hello(channel, channel.receive())
    while True:
        message = channel.receive()
        op = message["op"]
        if op == "describe":
            channel.send(worker.describe(message))
        elif op == "cook":
            channel.send(worker.cook(message))
        elif op == "bye":
            return
        else:
            raise Malformed(f"unknown op {op!r}")


def main():
    channel = Channel()
    signal.signal(signal.SIGINT, on_interrupt)
    try:
        serve(channel)
    except Stop as stop:
        if stop.message is not None:
            channel.send({"op": "fatal", "message": stop.message})
        return stop.status
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except BrokenPipeError:
        sys.exit(0)  # pyrograph went away: nobody is left to tell
