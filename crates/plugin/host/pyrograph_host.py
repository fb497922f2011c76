"""The pyrograph plugin worker: loads plugin files and cooks their nodes for the Rust process.

pyrograph starts it as `python3 -u pyrograph_host.py` with PYTHONPATH set to this folder and speaks
protocol v1 over stdin/stdout: each message is a 4-byte little-endian length and that many bytes
of UTF-8 JSON. Images travel through the arena, a shared file that both sides map; the messages
only carry offsets, shapes and dtypes. A whole-clip cook also talks while it runs: it asks for
the frames of its clip inputs and hands over the frames of its clip outputs one at a time
(pyrograph_host_clip.py).

Exit status: 0 after `bye` or when pyrograph closes the pipe, 1 when this Python cannot serve
(no numpy, another protocol, no arena), 2 after a malformed request. Both failures first send
`{"op": "fatal", "message": ...}`.
"""

import contextlib
import hashlib
import io
import linecache
import os
import platform
import signal
import sys
import time
import tokenize
import traceback
import types

import pyrograph_host_clip
import pyrograph_host_io
import pyrograph_plugin
from pyrograph_host_clip import REPLY_OPS, Exchange, Raised, clip_views, emit_clip
from pyrograph_host_io import (
    CHECKS, Arena, Channel, Malformed, PortError, Stop, array_spec, cancellable, count, field, np, on_interrupt,
    returned_values, shorten,
)

PROTOCOL = 1
FRAMES_KEPT = 5
VECTOR_SIZES = {"color": 4, "vec2": 2, "vec3": 3}
RAMP_WIDTHS = {"color_ramp": 4, "curve": 1}  # values per key, after the position
CONNECTIONS = ("image", "mask")  # the input kinds whose values come through the arena


class LoadError(Exception):
    """A plugin file failed to load; `error` is the {exception, message, frames} sent back."""

    def __init__(self, error):
        super().__init__(error["message"])
        self.error = error


# ---------------------------------------------------------------------------------------------
# Loading plugin files.


def frames_of(traceback_):
    """The last frames of a traceback outside this worker and the declaration API."""
    ours = {os.path.realpath(module.__file__) for module in (pyrograph_plugin, pyrograph_host_io, pyrograph_host_clip)}
    ours.add(os.path.realpath(__file__))
    frames = [f for f in traceback.extract_tb(traceback_) if os.path.realpath(f.filename) not in ours]
    return [
        {"file": f.filename, "line": f.lineno or 0, "function": f.name, "code": shorten(f.line or "")}
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
            "code": shorten((exception.text or "").strip()),
        })
    return {"exception": type(exception).__name__, "message": shorten(message), "frames": frames[-FRAMES_KEPT:]}


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
    elif kind in RAMP_WIDTHS:
        size = 1 + RAMP_WIDTHS[kind]
        rows = value if isinstance(value, list) else []
        if rows and all(isinstance(r, list) and len(r) == size and all(is_number(x) for x in r) for r in rows):
            keys = pyrograph_host_io.np.array(rows, dtype=pyrograph_host_io.np.float64)
            keys.flags.writeable = False
            return keys
    raise Malformed(f"parameter {port['name']!r} ({kind}) cannot be {value!r:.200}")


def is_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def arguments(declaration, request, arena, exchange):
    """The keyword arguments of a cook: parameters from JSON, images and masks from the arena,
    clips as views that fetch their frames when indexed."""
    params = field(request, "params", (dict,))
    arrays = field(request, "arrays", (dict,))
    clips = field(request, "clips", (dict,)) if "clips" in request else {}  # none to give: it may be left out
    ports = {port["name"]: port for port in declaration.inputs}
    arena.refresh()  # pyrograph grows the arena when a cook's inputs do not fit
    kwargs = {}
    for names, connection in ((params, False), (arrays, True)):
        for name, value in names.items():
            port = ports.get(name)
            if port is None or (port["kind"] in CONNECTIONS) != connection:
                raise Malformed(f"{declaration.type_name} has no {'array' if connection else 'parameter'} input {name!r}")
            kwargs[name] = arena.view(name, value) if connection else argument(port, value)
    kwargs.update(clip_views(declaration, clips, exchange))
    for port in declaration.inputs:
        if port["name"] not in kwargs and port["default"] is None:
            raise Malformed(f"{declaration.type_name}: the required input {port['name']!r} was not given")
    return kwargs


@contextlib.contextmanager
def running(frame):
    """The context plugin code runs in: cancellable, with current_frame() answering `frame`."""
    try:
        pyrograph_plugin._frame = frame
        with cancellable():
            yield
    finally:
        pyrograph_plugin._frame = None


def call(declaration, kwargs, frame):
    """Runs the node function, cancellable. A generator function only starts when its frames are
    taken, in emit_clip."""
    with running(frame):
        return declaration.function(**kwargs)


def error_reply(cook_id, kind, port=None, exception=None, message="", frames=()):
    return {"op": "error", "id": cook_id, "kind": kind, "port": port, "exception": exception,
            "message": message, "frames": list(frames)}


def plugin_failure(cook_id, exchange, exception):
    """The error reply for an exception raised by plugin code."""
    if exchange.is_frame_error(exception):
        # pyrograph knows why it could not make the frame, and reports the upstream node's error.
        return error_reply(cook_id, "frame_error", exception="FrameError", message=str(exception))
    return error_reply(cook_id, "exception", **error_of(exception))


class Worker:
    """Serves describe and cook once hello has opened the arena."""

    def __init__(self, channel, arena):
        self.channel = channel
        self.arena = arena
        self.plugins = Plugins()
        # A cook was cancelled while it waited for pyrograph's answer, which may still come.
        self.owed = False

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
        exchange = Exchange(self.channel, self.arena, cook_id)
        try:
            reply = self._cook(cook_id, request, exchange)
        finally:
            exchange.close()
            self.owed = exchange.owed
        if exchange.stop is not None:
            raise exchange.stop  # met in plugin code, which may have caught it: the channel is done
        if exchange.owed:
            # Cancelled while waiting for pyrograph: the cook is cancelled whatever the plugin
            # did with the KeyboardInterrupt.
            return error_reply(cook_id, "cancelled", exception="KeyboardInterrupt", message="the cook was cancelled")
        return reply

    def _cook(self, cook_id, request, exchange):
        type_name = field(request, "type", (str,))
        path = field(request, "file", (str,))
        sha256 = field(request, "sha256", (str,))
        frame = field(request, "frame", (int,), nullable=True)
        out_offset = count(request, "out_offset")
        cancelled = error_reply(cook_id, "cancelled", exception="KeyboardInterrupt", message="the cook was cancelled")
        started = time.perf_counter()
        try:
            with cancellable():  # a slow import at the top of a plugin file can be cancelled too
                loaded = self.plugins.load(path, sha256)
            declaration = loaded.nodes.get(type_name)
            if declaration is None:
                declared = ", ".join(loaded.nodes) or "no node types"
                return error_reply(cook_id, "load", message=f"{path} does not declare {type_name} (it declares {declared})")
            result = call(declaration, arguments(declaration, request, self.arena, exchange), frame)
        except LoadError as failure:
            return error_reply(cook_id, "load", **failure.error)
        except KeyboardInterrupt:
            return cancelled
        except Stop:
            raise
        except BaseException as exception:  # SystemExit too: a plugin cannot end the worker
            return plugin_failure(cook_id, exchange, exception)
        try:
            outputs = self.outputs(declaration, result, out_offset, exchange, frame)
        except KeyboardInterrupt:
            return cancelled
        except Raised as raised:  # plugin code, while its returned frames were taken
            return plugin_failure(cook_id, exchange, raised.error)
        except PortError as failure:
            text = f"output '{failure.port}': {failure}" if failure.port else str(failure)
            return error_reply(cook_id, "port", port=failure.port, message=text)
        except OSError as failure:  # the arena cannot grow: memory or the file system is full
            text = f"could not write the outputs into the shared file: {failure}"
            return error_reply(cook_id, "exception", exception=type(failure).__name__, message=text)
        except Stop:
            raise
        except Exception as failure:  # a value the checks choke on (10**400 as a float, a MemoryError)
            text = f"the returned value could not be read: {type(failure).__name__}: {failure}"
            return error_reply(cook_id, "port", message=text)
        ms = (time.perf_counter() - started) * 1000
        return {"op": "result", "id": cook_id, "outputs": outputs, "ms": round(ms, 3)}

    def outputs(self, declaration, result, out_offset, exchange, frame):
        """Checks the result against the declared outputs and writes them: the frames of each clip
        output one at a time (pyrograph copies each out before the next is written over it), then
        the other arrays, from out_offset."""
        ports = declaration.outputs
        # The outputs that are not clips are checked first, so a wrong one fails before any frame
        # is made.
        checked = [
            value if port["kind"] == "clip" else CHECKS[port["kind"]](port, value)
            for port, value in zip(ports, returned_values(declaration, result))
        ]
        clips = {
            port["name"]: emit_clip(exchange, port, value, out_offset, lambda: running(frame))
            for port, value in zip(ports, checked) if port["kind"] == "clip"
        }
        arrays = [value for port, value in zip(ports, checked) if port["kind"] != "clip" and isinstance(value, np.ndarray)]
        offsets = iter(self.arena.write(arrays, out_offset))
        outputs = []
        for port, value in zip(ports, checked):
            if port["kind"] == "clip":
                outputs.append(clips[port["name"]])
            elif isinstance(value, np.ndarray):
                outputs.append({"port": port["name"], "array": array_spec(value, next(offsets))})
            else:
                outputs.append({"port": port["name"], "value": value})
        return outputs


# ---------------------------------------------------------------------------------------------
# The session.


def hello(channel, message) -> Worker:
    """Answers hello: checks numpy and opens the arena, or stops with a fatal message."""
    if message["op"] != "hello":
        raise Malformed(f"the first message must be hello, got {message['op']!r}")
    protocol = field(message, "protocol", (int,))
    if protocol != PROTOCOL:
        raise Stop(1, f"this worker speaks protocol {PROTOCOL}, not {protocol}: its pyrograph_host.py is from another version")
    path = field(message, "arena", (str,))
    try:
        # Imported again, though pyrograph_host_io tried already, for the reason it failed.
        import numpy
    except Exception as error:  # a broken install raises more than ImportError
        raise Stop(1, f"numpy is not installed for {sys.executable} ({error}): install it (pip install numpy) "
                      "or point PYROGRAPH_PYTHON at a Python that has it") from None
    worker = Worker(channel, Arena(path))
    channel.send({"op": "ready", "protocol": PROTOCOL, "python": platform.python_version(),
                  "numpy": numpy.__version__, "pid": os.getpid()})
    return worker


def serve(channel):
    worker = hello(channel, channel.receive())
    while True:
        message = channel.receive()
        op = message["op"]
        owed, worker.owed = worker.owed, False
        if owed and op in REPLY_OPS:
            continue  # the answer to a cancelled cook's request, sent before pyrograph read the cancel
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
