# An example pyrograph node type written in Python: studio.heat_haze, the shimmer of hot air.
# pyrograph finds the plugins/ folder beside a graph by itself, so this renders the example graph:
#
#     pyrograph render examples/plugins/heat_haze/heat-haze.ron
import numpy as np
from pyrograph_plugin import Enum, Float, Image, node


@node("studio.heat_haze", category="Studio")
def heat_haze(
    image: Image(doc="Frame to distort"),
    amount: Float(range=(0.0, 20.0), doc="Displacement in pixels") = 4.0,
    wavelength: Float(range=(2.0, 400.0), doc="Wave length in pixels") = 40.0,
    axis: Enum("vertical", "horizontal", doc="Direction of the waves") = "vertical",
) -> Image:
    """Shimmers a frame with sine displacement, like air above a flame.

    Vertical waves shift each row sideways by amount·sin(2π·y/wavelength); horizontal waves shift
    each column up or down by amount·sin(2π·x/wavelength). Sub-pixel shifts blend the two nearest
    pixels, and pixels beyond the border repeat the edge.
    """
    if axis == "vertical":
        return _shift_rows(image, _wave(image.shape[0], amount, wavelength))
    # Shifting columns is shifting the rows of the transposed frame.
    columns = np.swapaxes(image, 0, 1)
    shifted = _shift_rows(columns, _wave(image.shape[1], amount, wavelength))
    return np.ascontiguousarray(np.swapaxes(shifted, 0, 1))


def _wave(count, amount, wavelength):
    """The shift in pixels of each of `count` rows."""
    return amount * np.sin(2 * np.pi * np.arange(count) / wavelength)


def _shift_rows(image, shifts):
    """Moves row y of a (H,W) or (H,W,C) image right by shifts[y] pixels, as float32."""
    width = image.shape[1]
    source = np.arange(width)[None, :] - shifts[:, None]  # where each output pixel reads from
    left = np.floor(source)
    t = (source - left).astype(np.float32)
    left = left.astype(np.intp)
    i0 = np.clip(left, 0, width - 1)
    i1 = np.clip(left + 1, 0, width - 1)
    if image.ndim == 3:  # the same shift for every channel of a pixel
        t, i0, i1 = t[..., None], i0[..., None], i1[..., None]
    a = np.take_along_axis(image, i0, axis=1)
    b = np.take_along_axis(image, i1, axis=1)
    return (a + (b - a) * t).astype(np.float32, copy=False)
