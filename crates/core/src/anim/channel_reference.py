"""Writes channel_reference.json: expected samples of animation channels, computed with SciPy.

This is the independent reference for channel.rs. Nothing here is shared with the Rust code: the
automatic ("smooth") slopes come from SciPy's PchipInterpolator, cubic segments are evaluated with
SciPy's CubicHermiteSpline, linear ones with numpy.interp, constant ones with interp1d(kind="previous"),
and linear extrapolation takes its slope from SciPy's derivative of the end segment.

Run:  python3 -m venv venv && venv/bin/pip install scipy && venv/bin/python channel_reference.py
It writes channel_reference.json next to this file.
"""

import json
import os

import numpy as np
from scipy.interpolate import CubicHermiteSpline, PchipInterpolator, interp1d


def key(frame, value, interp, in_slope=0.0, out_slope=0.0):
    return [float(frame), float(value), interp, float(in_slope), float(out_slope)]


def tan(frame, value, in_slope, out_slope):
    return key(frame, value, "tangent", in_slope, out_slope)


def auto_slopes(keys):
    """PCHIP derivatives at the keys, from SciPy (two keys: both the chord slope, as SciPy does)."""
    x = np.array([k[0] for k in keys])
    y = np.array([k[1] for k in keys])
    if len(keys) == 1:
        return np.zeros(1)
    return PchipInterpolator(x, y).derivative()(x)


def segment(keys, auto, i):
    """Key i -> key i+1 as (kind, callable f(x), callable df(x)) built from SciPy objects."""
    (f0, v0, m0, in0, out0), (f1, v1, m1, in1, out1) = keys[i], keys[i + 1]
    if m0 == "constant":
        return (lambda x: v0 if x < f1 else v1), (lambda x: 0.0)
    if m0 == "linear":
        return (lambda x: float(np.interp(x, [f0, f1], [v0, v1]))), (lambda x: (v1 - v0) / (f1 - f0))
    if m0 == "ease":
        d0, d1 = 0.0, 0.0
    else:
        d0 = out0 if m0 == "tangent" else auto[i]
        d1 = in1 if m1 == "tangent" else auto[i + 1]
    spline = CubicHermiteSpline([f0, f1], [v0, v1], [d0, d1])
    deriv = spline.derivative()
    return (lambda x: float(spline(x))), (lambda x: float(deriv(x)))


def whole_curve(keys):
    """The whole channel as one SciPy object when every segment has the same mode, else None."""
    x = np.array([k[0] for k in keys])
    y = np.array([k[1] for k in keys])
    modes = {k[2] for k in keys[:-1]}
    if len(modes) != 1:
        return None
    mode = modes.pop()
    if mode == "smooth":
        return lambda f: float(PchipInterpolator(x, y)(f))
    if mode == "linear":
        return lambda f: float(np.interp(f, x, y))
    if mode == "constant":
        return lambda f: float(interp1d(x, y, kind="previous")(f))
    if mode == "ease":
        return lambda f: float(CubicHermiteSpline(x, y, np.zeros_like(x))(f))
    return None


def inside(keys, auto, f):
    """The curve at a frame between the first and last key (inclusive)."""
    frames = [k[0] for k in keys]
    if f == frames[-1]:
        return keys[-1][1]
    i = int(np.searchsorted(frames, f, side="right")) - 1
    value, _ = segment(keys, auto, i)
    return value(f)


def evaluate(case, f):
    keys = case["keys"]
    auto = auto_slopes(keys)
    first, last = keys[0], keys[-1]
    if first[0] <= f <= last[0]:
        got = inside(keys, auto, f)
        whole = whole_curve(keys)
        if whole is not None:
            # Two independent routes (one SciPy object for the whole curve, or one per segment) agree.
            assert abs(whole(f) - got) < 1e-9, (case["name"], f, whole(f), got)
        return got
    before = f < first[0]
    mode = case["before"] if before else case["after"]
    end = first if before else last
    if mode == "hold" or len(keys) == 1:
        return end[1]
    if mode == "cycle":
        period = last[0] - first[0]
        return inside(keys, auto, first[0] + (f - first[0]) % period)
    # Linear: the derivative of the end segment at the end key.
    _, deriv = segment(keys, auto, 0 if before else len(keys) - 2)
    return end[1] + deriv(end[0]) * (f - end[0])


def sample_frames(keys):
    frames = [k[0] for k in keys]
    out = list(frames)
    for a, b in zip(frames, frames[1:]):
        out += [a + (b - a) * t for t in (0.1, 0.25, 0.5, 0.77, 0.93, 0.999)]
    first, last = frames[0], frames[-1]
    period = max(last - first, 1.0)
    for d in (0.5, 1.0, 0.3 * period, 1.3 * period, 3.7 * period + 0.2, 11.45 * period):
        out += [first - d, last + d]
    return sorted(set(out))


CASES = [
    ("one_key_hold", [key(10, 5, "smooth")], "hold", "hold"),
    ("one_key_linear_cycle", [key(10, -2.5, "linear")], "linear", "cycle"),
    ("one_key_tangent_linear", [tan(-3, 7, 4, -2)], "linear", "linear"),
    ("two_keys_smooth", [key(0, 1, "smooth"), key(8, 5, "smooth")], "linear", "linear"),
    ("two_keys_ease", [key(2, 1, "ease"), key(5, -3, "ease")], "linear", "cycle"),
    ("two_keys_constant", [key(0, 3, "constant"), key(4, 9, "linear")], "cycle", "linear"),
    ("two_keys_linear", [key(1, 3, "linear"), key(4.5, -4, "constant")], "linear", "hold"),
    ("two_keys_tangent", [tan(0, 0, 9, 2), tan(10, 4, -1, 5)], "linear", "linear"),
    ("smooth_monotone_uneven",
     [key(f, v, "smooth") for f, v in [(0, 0), (1, 0.5), (3, 2), (3.5, 4), (7, 4.2), (10, 9)]], "hold", "linear"),
    ("smooth_decreasing_uneven",
     [key(f, v, "smooth") for f, v in [(-5, 10), (-4.5, 9), (0, 8.7), (1, 2), (12, 1.5)]], "linear", "cycle"),
    ("smooth_sign_changes_flat_run",
     [key(f, v, "smooth") for f, v in [(0, 0), (2, 2), (3, -1), (5, -1), (6, 3), (9.5, 0.5), (10, 4)]], "cycle", "cycle"),
    ("smooth_flat_runs", [key(f, v, "smooth") for f, v in [(0, 1), (1, 1), (2, 1), (4, 2), (5, 2), (9, 3)]], "linear", "linear"),
    # Both ends hit SciPy's _edge_case clamps: a slope of the wrong sign (-> 0) and |d| > 3|delta0| (-> 3 delta0).
    ("smooth_edge_wrong_sign", [key(f, v, "smooth") for f, v in [(0, 0), (1, 1), (2, 6), (3, 11), (4, 12)]], "linear", "linear"),
    ("smooth_edge_clamp_three", [key(f, v, "smooth") for f, v in [(0, 0), (1, 1), (2, -4), (3, 1), (4, 0)]], "linear", "linear"),
    ("smooth_three_keys", [key(f, v, "smooth") for f, v in [(0, 0), (1, 3), (7, 4)]], "linear", "linear"),
    ("linear_uneven", [key(f, v, "linear") for f, v in [(-2, 1), (0.5, 4), (1, -3), (6, -3), (7.25, 10)]], "linear", "linear"),
    ("constant_steps", [key(f, v, "constant") for f, v in [(0, 1), (3, 4), (4, -2), (10, 7)]], "cycle", "linear"),
    ("ease_non_monotone", [key(f, v, "ease") for f, v in [(0, 0), (1.5, 5), (3, 2), (8, 2), (9, -6)]], "linear", "cycle"),
    ("tangent_overshoot",
     [tan(0, 0, 1, 3), tan(2, 1, -4, 0.5), tan(5, -2, 2, 2), tan(6, 3, 10, -7), tan(9, 0, -1, 8)], "linear", "linear"),
    ("mixed_all_modes",
     [key(0, 0, "constant"), key(2, 3, "linear"), key(3, 1, "smooth"), key(6, 4, "ease"), tan(7, 2, 1.5, -3),
      key(8, 0, "smooth"), tan(10, 5, 0.25, 2), key(12, 5, "smooth"), key(13, 7, "linear")], "linear", "linear"),
    ("mixed_smooth_into_tangent",
     [key(0, 1, "smooth"), key(1, 2, "smooth"), tan(4, 0, 6, -1), key(5, -2, "smooth"), key(9, 0, "ease")], "cycle", "linear"),
    ("mixed_ends_constant", [key(-1, 2, "linear"), key(0, 4, "smooth"), key(3, 1, "smooth"), key(5, 6, "constant"),
                             key(8, 9, "smooth")], "linear", "linear"),
    ("mixed_ends_ease", [tan(0, 1, 0, -2), key(2, -1, "smooth"), key(3, 4, "smooth"), key(6, 4, "ease"), key(7, 0, "linear")],
     "linear", "linear"),
    ("mixed_tangent_ends_linear", [tan(0, 0, 5, -1), key(1, 2, "constant"), key(2, 2.5, "ease"), tan(4, -1, 3, 0)],
     "cycle", "linear"),
    ("mixed_fractional_frames",
     [key(0.25, 3, "smooth"), key(0.5, 3.5, "linear"), key(1.75, 3.2, "smooth"), key(2, 0, "ease"), key(2.1, 0.5, "smooth"),
      key(4.8, 1, "constant"), key(5.5, 1, "smooth")], "cycle", "cycle"),
]


def main():
    out = []
    for name, keys, before, after in CASES:
        case = {"name": name, "keys": keys, "before": before, "after": after}
        case["samples"] = [[f, evaluate(case, f)] for f in sample_frames(keys)]
        out.append(case)
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "channel_reference.json")
    with open(path, "w") as fh:
        # One case per line, so a regenerated file diffs case by case.
        fh.write("[\n" + ",\n".join(json.dumps(c, separators=(",", ":")) for c in out) + "\n]\n")
    print(f"wrote {len(out)} cases, {sum(len(c['samples']) for c in out)} samples to {path}")


if __name__ == "__main__":
    main()
