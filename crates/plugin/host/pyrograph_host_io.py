"""What the plugin worker shares with pyrograph: message framing, the errors that end the
worker, the arena that carries arrays, SIGINT, and the checks on what a node function returns.

pyrograph_host.py (the worker loop) and pyrograph_host_clip.py (whole-clip cooks) both build on
this module; it imports neither, so each class here exists once however the worker was started.
"""

import contextlib
import json
import mmap
import os
import struct

try:
    import numpy as np
except Exception:  # noqa: BLE001  (a broken install raises more than ImportError)
    # hello imports numpy again and sends the reason as a fatal message; nothing here runs
    # before hello has succeeded.
    np = None

MAX_FRAME = 16 << 20
ALIGN = 64  # output arrays start on cache-line boundaries
TEXT_KEPT = 8000  # longest message or code line sent, so a plugin's huge message cannot burst a frame
DTYPES = ("<f4", "|u1")  # float32 images, uint8 masks


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
        # Bytes read but not yet taken as a message. They live here rather than in a local, so a
        # cook cancelled while it waits for a frame loses none of a message half read, and the
        # next receive goes on from there: the stream stays in step.
        self.pending = bytearray()

    def _fill(self, count):
        """Reads until at least `count` bytes are pending."""
        while len(self.pending) < count:
            chunk = os.read(self.inp, max(count - len(self.pending), 1 << 16))
            if not chunk:
                if self.pending:
                    raise Malformed(f"the input ended inside a frame ({len(self.pending)} of {count} bytes)")
                raise Stop(0)
            self.pending += chunk

    def receive(self) -> dict:
        self._fill(4)
        (length,) = struct.unpack("<I", self.pending[:4])
        if length > MAX_FRAME:
            raise Malformed(f"a frame of {length} bytes is over the {MAX_FRAME}-byte limit")
        self._fill(4 + length)
        body = bytes(self.pending[4:4 + length])
        del self.pending[:4 + length]
        try:
            message = json.loads(body)
        except ValueError as error:
            raise Malformed(f"a frame is not UTF-8 JSON: {error}") from None
        if not isinstance(message, dict) or not isinstance(message.get("op"), str):
            raise Malformed("a message must be a JSON object with a string \"op\"")
        return message

    def send(self, message):
        # "replace" turns lone surrogates (undecodable file names) into '?' rather than failing.
        # The messages sent while plugin code may be interrupted (need_frame, emit) are far under
        # PIPE_BUF, so each goes out whole or not at all.
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


def shorten(text):
    return text if len(text) <= TEXT_KEPT else text[:TEXT_KEPT] + " … (cut)"


# ---------------------------------------------------------------------------------------------
# SIGINT cancels the plugin code that is running; between cooks there is nothing to cancel, and
# raising there would end the worker.


_cancellable = False


def on_interrupt(signum, frame):
    if _cancellable:
        raise KeyboardInterrupt


@contextlib.contextmanager
def cancellable():
    """Lets SIGINT raise KeyboardInterrupt in the code run inside.

    Nestable: a whole-clip cook waits for pyrograph's answers both inside plugin code (view[i])
    and outside it (after emitting a frame), and leaving the inner wait must not end the outer."""
    global _cancellable
    outer = _cancellable
    try:
        _cancellable = True
        yield
    finally:
        _cancellable = outer


# ---------------------------------------------------------------------------------------------
# The arena.


class Arena:
    """The shared file. pyrograph may grow it between cooks and while it makes a frame, and so may
    a cook's outputs."""

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
    """The dtype an output array is written as: images stay float32, points float64, and masks
    (uint8 or bool) become uint8."""
    if array.dtype in (np.float32, np.float64):
        return array.dtype.newbyteorder("<")
    return np.dtype(np.uint8)


def array_spec(array, offset):
    """The {offset, shape, dtype} of an array written at `offset`."""
    return {"offset": offset, "shape": list(array.shape), "dtype": stored_dtype(array).str}


# ---------------------------------------------------------------------------------------------
# Checks on returned values.


def check_image(port, value):
    channels = port["channels"] or "any"
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


def check_points(port, value):
    """Emitter points as float64 (N,3) x,y,z or (N,4) seconds,x,y,z, C-contiguous."""
    expected = "expected an (N,3) or (N,4) array of finite numbers"
    if not isinstance(value, np.ndarray):
        raise PortError(port["name"], f"{expected}, got {type(value).__name__}")
    numeric = np.issubdtype(value.dtype, np.floating) or np.issubdtype(value.dtype, np.integer)
    if not numeric or value.ndim != 2 or value.shape[1] not in (3, 4) or value.shape[0] < 1:
        empty = ", which has no points" if numeric and value.ndim == 2 and value.shape[0] == 0 else ""
        raise PortError(port["name"], f"{expected}, got {value.dtype} {value.shape}{empty}")
    points = np.ascontiguousarray(value, dtype=np.float64)
    bad = ~np.isfinite(points).all(axis=1)
    if bad.any():
        row = int(np.argmax(bad))
        raise PortError(port["name"], f"{expected}, got {value.dtype} {value.shape} with {points[row].tolist()} in row {row}")
    # pyrograph's point lists start at time 0; say so here, naming the output, rather than later.
    if points.shape[1] == 4 and (points[:, 0] < 0).any():
        row = int(np.argmax(points[:, 0] < 0))
        raise PortError(port["name"], f"row {row}: the time (column 0, seconds) must be ≥ 0, got {points[row, 0]}")
    return points


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


# Clip outputs are not here: their frames are checked one at a time as they are emitted.
CHECKS = {
    "image": check_image, "mask": check_mask, "points": check_points,
    "float": check_value, "int": check_value, "bool": check_value,
}


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
