"""Whole-clip cooks: the talk with pyrograph while a whole-clip node runs.

A clip is never sent whole: it may be longer than memory. While the function runs, view[i] asks
for frame i (`need_frame`) and pyrograph answers with the frame written into the arena (`frame`)
or with why it could not make it (`frame_error`). A returned clip goes back a frame at a time:
each frame is written into the arena and announced (`emit`), and the next waits for pyrograph's
`ack`, since it reuses the same bytes. Both ways are strictly request and reply, so at most one
message is ever outstanding on the channel.
"""

import collections.abc
import math

import pyrograph_plugin
from pyrograph_host_io import (
    Malformed, PortError, Stop, array_spec, cancellable, check_image, count, field, np, shorten,
)

# The replies pyrograph may send while a cook waits on it; the worker loop drops one arriving
# after the cook was cancelled (pyrograph may have answered before it read the cancel).
REPLY_OPS = ("frame", "frame_error", "ack")

END = object()  # what next_frame returns after the last frame (a yielded None is a wrong frame)


class Raised(Exception):
    """Plugin code raised `error` while its returned frames were being consumed."""

    def __init__(self, error):
        super().__init__(str(error))
        self.error = error


class Exchange:
    """The requests of one cook to pyrograph, and what became of them."""

    def __init__(self, channel, arena, cook_id):
        self.channel = channel
        self.arena = arena
        self.cook_id = cook_id
        self.open = True  # until the cook replies: a view kept past it must not talk
        self.owed = False  # a request is sent and its reply not yet read
        self.stop = None  # a Stop met inside plugin code, which the plugin may have caught
        self.frame_errors = []  # the FrameErrors raised for pyrograph's frame_error replies

    def close(self):
        self.open = False

    def ask(self, request, replies):
        """Sends `request` and returns pyrograph's reply, whose op must be one of `replies`."""
        if self.stop is not None:
            raise self.stop
        if not self.open:
            raise RuntimeError("this clip belongs to a cook that has finished; use a clip only while the node runs")
        try:
            self.owed = True  # set first: a cancel right after the send must still know
            self.channel.send(request)
            with cancellable():
                reply = self.channel.receive()
            self.owed = False
            if reply["op"] == "bye":
                raise Stop(0)  # pyrograph is done with this worker, mid-cook or not
            if reply["op"] not in replies or count(reply, "id") != self.cook_id:
                raise Malformed(f"waiting for {' or '.join(replies)} for cook {self.cook_id}, got {shorten(repr(reply))}")
            return reply
        except Stop as stop:
            self.stop = stop  # re-raised after the function returns, even if the plugin caught it
            raise

    def frame(self, name, index):
        """Frame `index` of clip input `name`, as a read-only float32 copy."""
        reply = self.ask({"op": "need_frame", "id": self.cook_id, "clip": name, "index": index}, ("frame", "frame_error"))
        try:
            if reply["op"] == "frame_error":
                error = pyrograph_plugin.FrameError(shorten(field(reply, "message", (str,))))
                self.frame_errors.append(error)
                raise error
            self.arena.refresh()  # pyrograph grows the arena when a frame does not fit
            view = self.arena.view(f"{name}[{index}]", field(reply, "array", (dict,)))
            shape = view.shape
            if not (view.dtype == np.float32 and len(shape) in (2, 3) and shape[0] >= 1 and shape[1] >= 1
                    and shape[2:] in ((), (4,))):
                raise Malformed(f"frame {index} of clip {name!r} is {view.dtype} {shape}, not a float32 (H,W) or (H,W,4) image")
        except Stop as stop:
            self.stop = stop
            raise
        # A copy: pyrograph writes the next frame over these bytes.
        frame = view.copy()
        frame.flags.writeable = False
        return frame

    def emit(self, port, index, frame, out_offset):
        """Writes frame `index` of clip output `port` into the arena and waits until pyrograph has it."""
        (offset,) = self.arena.write([frame], out_offset)
        request = {"op": "emit", "id": self.cook_id, "port": port, "index": index, "array": array_spec(frame, offset)}
        self.ask(request, ("ack",))

    def is_frame_error(self, error):
        """Whether `error` is a FrameError pyrograph reported, rather than one the plugin made."""
        return any(error is e for e in self.frame_errors)


def clip_views(declaration, clips, exchange):
    """A ClipView for each clip input named in the request's `clips`: {name: {len, fps}}."""
    ports = {port["name"]: port for port in declaration.inputs}
    views = {}
    for name, spec in clips.items():
        if ports.get(name, {}).get("kind") != "clip":
            raise Malformed(f"{declaration.type_name} has no clip input {name!r}")
        length = count(spec, "len")
        fps = field(spec, "fps", (int, float))
        if not (math.isfinite(fps) and fps > 0):
            raise Malformed(f"clip {name!r}: fps must be a positive number, got {fps!r}")
        views[name] = pyrograph_plugin.ClipView._fetching(length, fps, lambda i, name=name: exchange.frame(name, i))
    return views


def returned_frames(port, value):
    """An iterator over the frames a function returned for clip output `port`."""
    if isinstance(value, np.ndarray):
        if value.ndim in (3, 4):
            return iter(value)  # frame k is value[k], a view
        raise PortError(port["name"], f"expected frames; an array of them has shape (N,H,W) or (N,H,W,4), "
                                      f"got {value.dtype} {value.shape}")
    if isinstance(value, (list, tuple, pyrograph_plugin.ClipView, collections.abc.Iterator)):
        return iter(value)
    raise PortError(port["name"], "expected frames: a generator, a list or tuple of float32 arrays, or a float32 array "
                                  f"of shape (N,H,W) or (N,H,W,4), got {type(value).__name__}")


def next_frame(frames, running):
    """The next frame, or END; plugin code computes it, so its errors become Raised."""
    try:
        with running():
            return next(frames)
    except StopIteration:
        return END
    except (KeyboardInterrupt, Stop):
        raise
    except BaseException as error:  # SystemExit too: a plugin cannot end the worker
        raise Raised(error) from None


def emit_clip(exchange, port, value, out_offset, running):
    """Emits a returned clip frame by frame, each checked before it is written; its result entry.

    A generator is consumed lazily, so frame k is made, emitted and acknowledged before the
    function starts on frame k+1. `running` is the context plugin code runs in (cancellable)."""
    name = port["name"]
    frames = returned_frames(port, value)
    first = None
    index = 0
    try:
        while True:
            frame = next_frame(frames, running)
            if frame is END:
                break
            try:
                check_image(port, frame)
            except PortError as failure:
                raise PortError(name, f"frame {index}: {failure}") from None
            if first is None:
                first = frame.shape
            elif frame.shape != first:
                raise PortError(name, f"frame {index}: expected the shape of frame 0, {first}, got {frame.shape}")
            exchange.emit(name, index, frame, out_offset)
            index += 1
    except BaseException:
        exchange.close()  # the cook is failing: the generator's cleanup must not ask for frames
        close = getattr(frames, "close", None)
        if close is not None:
            try:
                with running():
                    close()
            except BaseException:  # noqa: BLE001  (the first error is the one to report)
                pass
        raise
    if index == 0:
        raise PortError(name, "the clip has no frames")
    return {"port": name, "frames": index}
