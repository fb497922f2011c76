"""The peer of the harness's volume-render row: `volume.render`'s march written for NVIDIA Warp's
CPU device, on the dense N³ box examples/kernels/render.rs renders (nodes/volume/src/render has
the algorithms), step for step:

- the sun's transmittance volume by a sweep (render/sweep.rs): slice by slice along the sun's
  dominant axis from its side, each voxel's transmittance its upstream neighbour's (one slice
  toward the sun, read bilinearly) times the segment's Beer–Lambert factor (trapezoid), a ray in
  voxel steps where an upstream corner lies outside the box;
- a ray per pixel from the near plane (render/march.rs): through the box in steps of half a
  voxel, jittered per pixel by the same SplitMix64 hash, each step a homogeneous Beer–Lambert
  segment scattering the sun once (its transmittance read trilinearly, Henyey–Greenstein phase)
  plus an unshadowed ambient term, until the ray is opaque (transmittance < 10⁻³);
- empty space skipped as render/clear.rs skips it: the box's 8³ bricks whose samples read only
  zeros (the brick and the one-voxel shell around it) are flagged first, and a step whose nearest
  voxel lies in a flagged brick jumps to where the ray leaves that brick.

Warp's CPU device runs each kernel on one thread. Prints one JSON line like examples/kernels and
writes the frame (H×W×4 float32, straight RGBA) with --output.

    python benches/peers/warp_render.py --n 128 --width 640 --height 360 --reps 3 --output peer.npy
"""
import argparse
import json
import math
import statistics
import time

import numpy as np
import warp as wp

wp.config.quiet = True

# The scene, as examples/kernels/render.rs has it.
EYE, TARGET, FOV, NEAR, FAR = (0.5, 0.55, 2.0), (0.5, 0.4, 0.5), 40.0, 0.1, 100.0
SUN, SUN_COLOR = (0.5, 1.0, 0.3), 6.0
EXTINCTION, ALBEDO, G, AMBIENT, STEP = 8.0, 0.85, 0.3, 0.2, 0.5

# The grid type, the zero-outside read and the trilinear sample are the smoke peer's.
from warp_smoke import Field as Grid  # noqa: E402
from warp_smoke import trilinear  # noqa: E402


@wp.func
def exit_distance(p: wp.vec3, d: wp.vec3):
    t = float(1.0e30)
    for k in range(3):
        if d[k] > 1.0e-12:
            t = wp.min(t, (1.0 - p[k]) / d[k])
        elif d[k] < -1.0e-12:
            t = wp.min(t, (0.0 - p[k]) / d[k])
    return wp.max(t, 0.0)


@wp.func
def shadow_ray(dens: Grid, p: wp.vec3, toward: wp.vec3, h: float):
    # The transmittance toward the sun from world point p, marched in voxel steps.
    exit = exit_distance(p, toward)
    s = 0.5 * h
    depth = float(0.0)
    while s < exit:
        q = (p + toward * s) / h - wp.vec3(0.5, 0.5, 0.5)
        depth += trilinear(dens, q)
        if depth * h * EXTINCTION > 12.0:
            break
        s += h
    return wp.exp(-EXTINCTION * depth * h)


@wp.kernel
def sweep_slice(dens: Grid, trans: Grid, y: int, u: wp.vec3, toward: wp.vec3, h: float, step: float):
    # One slice of the sweep along +y (the sun's dominant axis): voxel (x, y, z) from slice y + 1.
    z, x = wp.tid()
    n = dens.shape[0]
    qz = float(z) + u[2]
    qx = float(x) + u[0]
    z0 = int(wp.floor(qz))
    x0 = int(wp.floor(qx))
    fz = qz - float(z0)
    fx = qx - float(x0)
    t = float(0.0)
    rho = float(0.0)
    outside = bool(False)
    for corner in range(4):
        cz = z0 + (corner & 1)
        cx = x0 + ((corner >> 1) & 1)
        w = wp.where((corner & 1) == 1, fz, 1.0 - fz) * wp.where(((corner >> 1) & 1) == 1, fx, 1.0 - fx)
        if w > 0.0:
            if y + 1 >= n or cz < 0 or cz >= n or cx < 0 or cx >= n:
                outside = True
            else:
                t += w * trans[cz, y + 1, cx]
                rho += w * dens[cz, y + 1, cx]
    if outside:
        p = (wp.vec3(float(x), float(y), float(z)) + wp.vec3(0.5, 0.5, 0.5)) * h
        trans[z, y, x] = shadow_ray(dens, p, toward, h)
    else:
        trans[z, y, x] = t * wp.exp(-EXTINCTION * step * 0.5 * (dens[z, y, x] + rho))


@wp.kernel
def clear_bricks(dens: Grid, clear: wp.array3d(dtype=wp.int32)):
    # A brick is clear when it and the one-voxel shell around it hold nothing above 0.
    bz, by, bx = wp.tid()
    n = dens.shape[0]
    empty = int(1)
    for z in range(wp.max(bz * 8 - 1, 0), wp.min(bz * 8 + 9, n)):
        for y in range(wp.max(by * 8 - 1, 0), wp.min(by * 8 + 9, n)):
            for x in range(wp.max(bx * 8 - 1, 0), wp.min(bx * 8 + 9, n)):
                if not (dens[z, y, x] <= 0.0):
                    empty = 0
    clear[bz, by, bx] = empty


@wp.func
def brick_exit(p: wp.vec3, d: wp.vec3, lo: wp.vec3, hi: wp.vec3):
    # How far from p (inside the box lo..hi) along d until the ray leaves it.
    t = float(1.0e30)
    for k in range(3):
        if d[k] > 1.0e-12:
            t = wp.min(t, (hi[k] - p[k]) / d[k])
        elif d[k] < -1.0e-12:
            t = wp.min(t, (lo[k] - p[k]) / d[k])
    return wp.max(t, 0.0)


@wp.func
def henyey_greenstein(c: float, g: float):
    denom = wp.max(1.0 + g * g - 2.0 * g * c, 1.0e-6)
    return (1.0 - g * g) / (4.0 * wp.pi * denom * wp.sqrt(denom))


@wp.kernel
def march(dens: Grid, trans: Grid, clear: wp.array3d(dtype=wp.int32), near: wp.array2d(dtype=wp.vec3), far: wp.array2d(dtype=wp.vec3),
          jitter: wp.array2d(dtype=wp.float32), toward: wp.vec3, h: float, out: wp.array3d(dtype=wp.float32)):
    row, col = wp.tid()
    o = near[row, col]
    length = wp.length(far[row, col] - o)
    d = (far[row, col] - o) / wp.max(length, 1.0e-30)
    # The box [0, 1]³ by slabs.
    t0 = float(-1.0e30)
    t1 = float(1.0e30)
    hit = bool(True)
    for k in range(3):
        if wp.abs(d[k]) < 1.0e-12:
            if o[k] < 0.0 or o[k] > 1.0:
                hit = False
        else:
            a = (0.0 - o[k]) / d[k]
            b = (1.0 - o[k]) / d[k]
            t0 = wp.max(t0, wp.min(a, b))
            t1 = wp.min(t1, wp.max(a, b))
    colour = float(0.0)
    transmit = float(1.0)
    if hit and t0 <= t1 and t1 >= 0.0:
        t0 = wp.max(t0, 0.0)
        t1 = wp.min(t1, length)
        step = STEP * h
        start = t0 + jitter[row, col] * step
        phase = henyey_greenstein(wp.dot(toward, d), G)
        k = int(0)
        while True:
            t = start + float(k) * step
            if t >= t1 or transmit < 1.0e-3:
                break
            p = o + d * t
            ip = p / h - wp.vec3(0.5, 0.5, 0.5)
            # The brick of the nearest voxel: outside the box or clear, jump past it.
            c = wp.vec3(wp.floor((ip[0] + 0.5) / 8.0), wp.floor((ip[1] + 0.5) / 8.0), wp.floor((ip[2] + 0.5) / 8.0))
            nb = clear.shape[0]
            cx = int(c[0])
            cy = int(c[1])
            cz = int(c[2])
            skip = bool(True)
            if cx >= 0 and cy >= 0 and cz >= 0 and cx < nb and cy < nb and cz < nb:
                skip = clear[cz, cy, cx] == 1
            if skip:
                lo = c * (8.0 * h)
                ex = t + brick_exit(p, d, lo, lo + wp.vec3(8.0 * h, 8.0 * h, 8.0 * h))
                k = wp.max(int(wp.floor((ex - start) / step)) + 1, k + 1)
                continue
            k += 1
            dt = wp.min(step, t1 - t)
            sigma = EXTINCTION * wp.max(trilinear(dens, ip), 0.0)
            a = wp.exp(-sigma * dt)
            through = transmit * wp.where(sigma > 1.0e-8, (1.0 - a) / sigma, dt)
            if sigma > 0.0:
                inscatter = AMBIENT + SUN_COLOR * trilinear(trans, ip) * phase
                colour += ALBEDO * sigma * through * inscatter
            transmit *= a
    out[row, col, 0] = colour
    out[row, col, 1] = colour
    out[row, col, 2] = colour
    out[row, col, 3] = 1.0


def blob(n):
    # Twice examples/kernels/smoke.rs's blob, in float64 as it computes it.
    z, y, x = np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij")
    d = np.sqrt((x - n / 2) ** 2 + (y - n / 4) ** 2 + (z - n / 2) ** 2)
    return 2.0 * np.clip(1.0 - d / (n / 6), 0.0, 1.0).astype(np.float32)


def matrices(w, h):
    # glam's Mat4::look_at_rh and Mat4::perspective_rh (depth 0..1), as pyrograph's camera.
    eye, target = np.array(EYE, dtype=np.float64), np.array(TARGET, dtype=np.float64)
    f = (target - eye) / np.linalg.norm(target - eye)
    s = np.cross(f, [0.0, 1.0, 0.0])
    s /= np.linalg.norm(s)
    u = np.cross(s, f)
    view = np.array([[*s, -s @ eye], [*u, -u @ eye], [*(-f), f @ eye], [0, 0, 0, 1]])
    fy = 1.0 / math.tan(math.radians(FOV) / 2)
    r = FAR / (NEAR - FAR)
    proj = np.array([[fy / (w / h), 0, 0, 0], [0, fy, 0, 0], [0, 0, r, r * NEAR], [0, 0, -1, 0]])
    return np.linalg.inv(proj @ view)


def rays(w, h):
    inv = matrices(w, h)
    x = (np.arange(w) + 0.5) / w * 2 - 1
    y = 1 - (np.arange(h) + 0.5) / h * 2
    xx, yy = np.meshgrid(x, y)

    def unproject(z):
        p = np.stack([xx, yy, np.full_like(xx, z), np.ones_like(xx)], axis=-1) @ inv.T
        return (p[..., :3] / p[..., 3:]).astype(np.float32)

    return unproject(0.0), unproject(1.0)


def jitters(w, h, seed=0):
    # render/march.rs's hash01: SplitMix64's finaliser of the seed, row and column.
    m = np.uint64(0xFFFFFFFFFFFFFFFF)
    with np.errstate(over="ignore"):
        row = np.arange(h, dtype=np.uint64)[:, None]
        col = np.arange(w, dtype=np.uint64)[None, :]
        z = (np.uint64(seed) * np.uint64(0x9E3779B97F4A7C15)) ^ (row * np.uint64(0xBF58476D1CE4E5B9)) ^ (col + np.uint64(0x94D049BB133111EB))
        z = ((z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)) & m
        z = ((z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)) & m
        z = z ^ (z >> np.uint64(31))
    return ((z >> np.uint64(40)).astype(np.float64) / float(1 << 24)).astype(np.float32)


class Renderer:
    def __init__(self, n, w, h):
        self.n, self.w, self.h = n, w, h
        self.dens = wp.array(blob(n), dtype=wp.float32)
        self.trans = wp.zeros((n, n, n), dtype=wp.float32)
        self.clear = wp.zeros((n // 8, n // 8, n // 8), dtype=wp.int32)
        near, far = rays(w, h)
        self.near = wp.array(near, dtype=wp.vec3)
        self.far = wp.array(far, dtype=wp.vec3)
        self.jitter = wp.array(jitters(w, h), dtype=wp.float32)
        self.out = wp.zeros((h, w, 4), dtype=wp.float32)

    def render(self):
        n, hvox = self.n, 1.0 / self.n
        toward = np.array(SUN) / np.linalg.norm(SUN)
        u = toward / abs(toward[1])
        step = float(np.linalg.norm(u)) * hvox
        for y in range(n - 1, -1, -1):
            wp.launch(sweep_slice, dim=(n, n), inputs=[self.dens, self.trans, y, wp.vec3(*u), wp.vec3(*toward), hvox, step])
        wp.launch(clear_bricks, dim=(n // 8, n // 8, n // 8), inputs=[self.dens, self.clear])
        wp.launch(march, dim=(self.h, self.w),
                  inputs=[self.dens, self.trans, self.clear, self.near, self.far, self.jitter, wp.vec3(*toward), hvox, self.out])
        wp.synchronize()


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=128)
    ap.add_argument("--width", type=int, default=640)
    ap.add_argument("--height", type=int, default=360)
    ap.add_argument("--reps", type=int, default=1)
    ap.add_argument("--warmup", type=int, default=0, help="untimed runs at the full size (kernels compile on a 16³ box first)")
    ap.add_argument("--output")
    a = ap.parse_args()
    wp.init()
    # Compile (or load from Warp's kernel cache) every kernel outside the timed runs.
    Renderer(16, 8, 8).render()
    r = Renderer(a.n, a.width, a.height)
    times = []
    for rep in range(a.warmup + a.reps):
        start = time.perf_counter()
        r.render()
        if rep >= a.warmup:
            times.append(time.perf_counter() - start)
    if a.output:
        np.save(a.output, r.out.numpy())
    print(json.dumps({"op": "render", "tool": "warp " + wp.__version__, "times_s": times,
                      "median_s": statistics.median(times), "threads": 1, "n": a.n,
                      "width": a.width, "height": a.height}))


if __name__ == "__main__":
    main()
