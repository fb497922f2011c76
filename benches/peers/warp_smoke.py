"""The peer of the harness's smoke-step row: `volume.simulate`'s sub-step written for NVIDIA Warp's
CPU device, on a dense N³ box, step for step the algorithm pyrograph runs (examples/kernels/smoke.rs
drives pyrograph's own sub-step; nodes/volume/src/sim has the algorithms):

- MacCormack advection with Selle et al.'s clamp (sim/advect.rs): scalars ride the voxel-centred
  velocity, each staggered component the mean of the centred velocities either side of its face;
  trilinear samples read 0 outside the box;
- cooling and dissipation (sim/combust.rs; no fuel burns, so no expansion);
- buoyancy on the vertical faces (sim/forces.rs, Fedkiw, Stam & Jensen 2001 eq. 8);
- the pressure projection (sim/pressure.rs, sim/multigrid.rs): voxels whose next voxel on every
  axis is inside the box are solved for, pressure 0 beyond; conjugate gradients preconditioned by
  one multigrid V-cycle (McAdams, Sifakis & Teran 2010: 2 red-black Gauss-Seidel sweeps down and
  up, 16 on the coarsest 8³ level, restriction ½ Σ children, piecewise-constant prolongation),
  warm-started from the last pressure, to the same tolerance on every voxel's divergence, with
  the same restart from the true residual; dot products in float64.

Warp's CPU device runs each kernel on one thread. Prints one JSON line like examples/kernels:
the time per sub-step of each timed run (each run starts from the blob again), their median, the
iterations, and writes density, temperature and u, v, w (5×N×N×N float32, z, y, x) with --output.

    python benches/peers/warp_smoke.py --n 128 --steps 4 --reps 1 --output peer.npy
"""
import argparse
import json
import statistics
import time

import numpy as np
import warp as wp

wp.config.quiet = True

# The sub-step's parameters, as examples/kernels/smoke.rs has them.
BUOYANCY, SMOKE_WEIGHT, COOLING, DISSIPATION = 2.0, 0.1, 0.6, 0.05
DT = 1.0 / 48.0
TOLERANCE, MAX_ITERATIONS = 0.01, 200
SWEEPS, COARSEST_SWEEPS = 2, 16

Field = wp.array3d(dtype=wp.float32)


@wp.func
def at(f: Field, x: int, y: int, z: int):
    n = f.shape[0]
    if x < 0 or y < 0 or z < 0 or x >= n or y >= n or z >= n:
        return float(0.0)
    return f[z, y, x]


@wp.func
def trilinear(f: Field, p: wp.vec3):
    x0 = int(wp.floor(p[0]))
    y0 = int(wp.floor(p[1]))
    z0 = int(wp.floor(p[2]))
    fx = p[0] - float(x0)
    fy = p[1] - float(y0)
    fz = p[2] - float(z0)
    s = float(0.0)
    for k in range(8):
        dx = k & 1
        dy = (k >> 1) & 1
        dz = k >> 2
        w = wp.where(dx == 1, fx, 1.0 - fx) * wp.where(dy == 1, fy, 1.0 - fy) * wp.where(dz == 1, fz, 1.0 - fz)
        s += w * at(f, x0 + dx, y0 + dy, z0 + dz)
    return s


@wp.func
def corner_range(f: Field, p: wp.vec3):
    x0 = int(wp.floor(p[0]))
    y0 = int(wp.floor(p[1]))
    z0 = int(wp.floor(p[2]))
    lo = float(1e30)
    hi = float(-1e30)
    for k in range(8):
        v = at(f, x0 + (k & 1), y0 + ((k >> 1) & 1), z0 + (k >> 2))
        lo = wp.min(lo, v)
        hi = wp.max(hi, v)
    return wp.vec2(lo, hi)


@wp.kernel
def centred(u: Field, v: Field, w: Field, scale: float, out: wp.array3d(dtype=wp.vec3)):
    z, y, x = wp.tid()
    n = u.shape[0]
    cu = 0.5 * (u[z, y, x] + wp.where(x + 1 < n, u[z, y, wp.min(x + 1, n - 1)], u[z, y, x]))
    cv = 0.5 * (v[z, y, x] + wp.where(y + 1 < n, v[z, wp.min(y + 1, n - 1), x], v[z, y, x]))
    cw = 0.5 * (w[z, y, x] + wp.where(z + 1 < n, w[wp.min(z + 1, n - 1), y, x], w[z, y, x]))
    out[z, y, x] = wp.vec3(cu, cv, cw) * scale


@wp.kernel
def face_displacement(c: wp.array3d(dtype=wp.vec3), axis: int, out: wp.array3d(dtype=wp.vec3)):
    z, y, x = wp.tid()
    here = c[z, y, x]
    below = here
    if axis == 0 and x > 0:
        below = c[z, y, x - 1]
    if axis == 1 and y > 0:
        below = c[z, y - 1, x]
    if axis == 2 and z > 0:
        below = c[z - 1, y, x]
    out[z, y, x] = 0.5 * (here + below)


@wp.kernel
def forward(f: Field, d: wp.array3d(dtype=wp.vec3), hat: Field):
    z, y, x = wp.tid()
    hat[z, y, x] = trilinear(f, wp.vec3(float(x), float(y), float(z)) - d[z, y, x])


@wp.kernel
def correct(f: Field, hat: Field, d: wp.array3d(dtype=wp.vec3), out: Field):
    z, y, x = wp.tid()
    p = wp.vec3(float(x), float(y), float(z))
    round_trip = trilinear(hat, p + d[z, y, x])
    corrected = hat[z, y, x] + 0.5 * (f[z, y, x] - round_trip)
    r = corner_range(f, p - d[z, y, x])
    out[z, y, x] = wp.min(wp.max(corrected, r[0]), r[1])


@wp.kernel
def decay(f: Field, factor: float):
    z, y, x = wp.tid()
    f[z, y, x] = f[z, y, x] * factor


@wp.kernel
def buoyancy(v: Field, temp: Field, dens: Field, dt: float):
    z, y, x = wp.tid()
    t = 0.5 * (temp[z, y, x] + at(temp, x, y - 1, z))
    d = 0.5 * (dens[z, y, x] + at(dens, x, y - 1, z))
    v[z, y, x] = v[z, y, x] + dt * (BUOYANCY * t - SMOKE_WEIGHT * d)


@wp.kernel
def rhs(u: Field, v: Field, w: Field, diag: Field, b: Field):
    z, y, x = wp.tid()
    if diag[z, y, x] > 0.0:
        flux = (at(u, x + 1, y, z) - u[z, y, x]) + (at(v, x, y + 1, z) - v[z, y, x]) + (at(w, x, y, z + 1) - w[z, y, x])
        b[z, y, x] = -flux
    else:
        b[z, y, x] = 0.0


@wp.func
def neighbours(f: Field, x: int, y: int, z: int):
    return at(f, x - 1, y, z) + at(f, x + 1, y, z) + at(f, x, y - 1, z) + at(f, x, y + 1, z) + at(f, x, y, z - 1) + at(f, x, y, z + 1)


@wp.kernel
def apply(diag: Field, x: Field, out: Field):
    k, j, i = wp.tid()
    d = diag[k, j, i]
    out[k, j, i] = wp.where(d > 0.0, d * x[k, j, i] - neighbours(x, i, j, k), 0.0)


@wp.kernel
def sweep(diag: Field, b: Field, colour: int, x: Field):
    # One colour's voxels read only the other colour's: updating in place is the red-black sweep.
    k, j, i = wp.tid()
    d = diag[k, j, i]
    if d > 0.0 and ((i + j + k) & 1) == colour:
        x[k, j, i] = (b[k, j, i] + neighbours(x, i, j, k)) / d


@wp.kernel
def residual(diag: Field, x: Field, b: Field, out: Field):
    k, j, i = wp.tid()
    d = diag[k, j, i]
    out[k, j, i] = wp.where(d > 0.0, b[k, j, i] - (d * x[k, j, i] - neighbours(x, i, j, k)), 0.0)


@wp.kernel
def restrict(r: Field, coarse_diag: Field, out: Field):
    k, j, i = wp.tid()
    s = float(0.0)
    for c in range(8):
        s += 0.5 * r[2 * k + (c >> 2), 2 * j + ((c >> 1) & 1), 2 * i + (c & 1)]
    out[k, j, i] = wp.where(coarse_diag[k, j, i] > 0.0, s, 0.0)


@wp.kernel
def prolong(coarse: Field, diag: Field, x: Field):
    k, j, i = wp.tid()
    if diag[k, j, i] > 0.0:
        x[k, j, i] = x[k, j, i] + coarse[k // 2, j // 2, i // 2]


@wp.kernel
def dot(a: Field, b: Field, out: wp.array(dtype=wp.float64)):
    k, j, i = wp.tid()
    wp.atomic_add(out, 0, wp.float64(a[k, j, i]) * wp.float64(b[k, j, i]))


@wp.kernel
def max_abs(a: Field, out: wp.array(dtype=wp.float32)):
    k, j, i = wp.tid()
    wp.atomic_max(out, 0, wp.abs(a[k, j, i]))


@wp.kernel
def axpy(alpha: float, x: Field, y: Field):
    k, j, i = wp.tid()
    y[k, j, i] = y[k, j, i] + alpha * x[k, j, i]


@wp.kernel
def xpby(x: Field, beta: float, y: Field):
    k, j, i = wp.tid()
    y[k, j, i] = x[k, j, i] + beta * y[k, j, i]


@wp.kernel
def subtract_gradient(p: Field, diag: Field, axis: int, vel: Field):
    k, j, i = wp.tid()
    di = wp.where(axis == 0, 1, 0)
    dj = wp.where(axis == 1, 1, 0)
    dk = wp.where(axis == 2, 1, 0)
    fluid_here = diag[k, j, i] > 0.0
    fluid_below = at(diag, i - di, j - dj, k - dk) > 0.0
    if fluid_here or fluid_below:
        vel[k, j, i] = vel[k, j, i] - (p[k, j, i] - at(p, i - di, j - dj, k - dk))


class Solver:
    """The arrays of an N³ box and its multigrid hierarchy (N, N/2, … down to one 8³ brick, as
    pyrograph's hierarchy of a dense box of bricks)."""

    def __init__(self, n):
        self.n = n
        self.h = 1.0 / n
        z = lambda m: wp.zeros((m, m, m), dtype=wp.float32, device="cpu")
        self.sizes = [n]
        while (self.sizes[-1] // 8) ** 3 > 2:
            self.sizes.append(self.sizes[-1] // 2)
        # Level 0 solves for voxels whose next voxel on every axis is inside the box; a coarse
        # voxel is solved for when any of its children is (all of them, in a box).
        d0 = np.zeros((n, n, n), np.float32)
        d0[: n - 1, : n - 1, : n - 1] = 6.0
        self.diag = [wp.array(d0, device="cpu")] + [wp.array(np.full((m, m, m), 6.0, np.float32), device="cpu")
                                                      for m in self.sizes[1:]]
        self.xs = [z(m) for m in self.sizes]
        self.bs = [z(m) for m in self.sizes]
        self.scratch = [z(m) for m in self.sizes]
        self.r, self.zv, self.p, self.q, self.b = z(n), z(n), z(n), z(n), z(n)
        self.f64 = wp.zeros(1, dtype=wp.float64, device="cpu")
        self.f32 = wp.zeros(1, dtype=wp.float32, device="cpu")
        self.dim = (n, n, n)

    def launch(self, kernel, level, inputs):
        m = self.sizes[level]
        wp.launch(kernel, dim=(m, m, m), inputs=inputs, device="cpu")

    def dot(self, a, b):
        self.f64.zero_()
        wp.launch(dot, dim=self.dim, inputs=[a, b, self.f64], device="cpu")
        return float(self.f64.numpy()[0])

    def max_abs(self, a):
        self.f32.zero_()
        wp.launch(max_abs, dim=self.dim, inputs=[a, self.f32], device="cpu")
        return float(self.f32.numpy()[0])

    def smooth(self, level, count, order):
        for _ in range(count):
            for colour in order:
                self.launch(sweep, level, [self.diag[level], self.bs[level], colour, self.xs[level]])

    def v_cycle(self, r, out):
        """out = M⁻¹ r, one V-cycle from zero."""
        last = len(self.sizes) - 1
        wp.copy(self.bs[0], r)
        for l in range(last + 1):
            self.xs[l].zero_()
            if l == last:
                self.smooth(l, COARSEST_SWEEPS, (0, 1))
                self.smooth(l, COARSEST_SWEEPS, (1, 0))
                break
            self.smooth(l, SWEEPS, (0, 1))
            self.launch(residual, l, [self.diag[l], self.xs[l], self.bs[l], self.scratch[l]])
            self.launch(restrict, l + 1, [self.scratch[l], self.diag[l + 1], self.bs[l + 1]])
        for l in range(last - 1, -1, -1):
            self.launch(prolong, l, [self.xs[l + 1], self.diag[l], self.xs[l]])
            self.smooth(l, SWEEPS, (1, 0))
        wp.copy(out, self.xs[0])

    def pcg(self, x, stop, budget):
        """(converged or stalled, iterations): conjugate gradients on A x = b from x."""
        d = self.diag[0]
        self.launch(residual, 0, [d, x, self.b, self.r])
        if self.max_abs(self.r) <= stop:
            return True, 0
        self.v_cycle(self.r, self.zv)
        wp.copy(self.p, self.zv)
        rz = self.dot(self.r, self.zv)
        for it in range(budget):
            self.launch(apply, 0, [d, self.p, self.q])
            pq = self.dot(self.p, self.q)
            if pq <= 0.0 or not np.isfinite(pq):
                return True, it + 1
            alpha = float(np.float32(rz / pq))
            self.launch(axpy, 0, [alpha, self.p, x])
            self.launch(axpy, 0, [-alpha, self.q, self.r])
            if self.max_abs(self.r) <= stop:
                return True, it + 1
            self.v_cycle(self.r, self.zv)
            rz_new = self.dot(self.r, self.zv)
            if rz == 0.0 or not np.isfinite(rz_new):
                return True, it + 1
            beta = float(np.float32(rz_new / rz))
            rz = rz_new
            self.launch(xpby, 0, [self.zv, beta, self.p])
        return False, budget

    def project(self, s):
        d = self.diag[0]
        self.launch(rhs, 0, [s["u"], s["v"], s["w"], d, self.b])
        stop = TOLERANCE * self.h
        iterations = 0
        while iterations < MAX_ITERATIONS:
            done, it = self.pcg(s["pressure"], 0.5 * stop, MAX_ITERATIONS - iterations)
            iterations += it
            self.launch(residual, 0, [d, s["pressure"], self.b, self.r])
            if self.max_abs(self.r) <= stop or not done:
                break
        for axis, name in enumerate("uvw"):
            self.launch(subtract_gradient, 0, [s["pressure"], d, axis, s[name]])
        return iterations

    def advect(self, s, dt):
        n = self.n
        scale = dt / self.h
        c = wp.zeros((n, n, n), dtype=wp.vec3, device="cpu")
        df = wp.zeros((n, n, n), dtype=wp.vec3, device="cpu")
        hat = wp.zeros((n, n, n), dtype=wp.float32, device="cpu")
        wp.launch(centred, dim=self.dim, inputs=[s["u"], s["v"], s["w"], scale, c], device="cpu")
        moved = {}
        for name in ("density", "temperature"):
            out = wp.zeros((n, n, n), dtype=wp.float32, device="cpu")
            wp.launch(forward, dim=self.dim, inputs=[s[name], c, hat], device="cpu")
            wp.launch(correct, dim=self.dim, inputs=[s[name], hat, c, out], device="cpu")
            moved[name] = out
        for axis, name in enumerate("uvw"):
            out = wp.zeros((n, n, n), dtype=wp.float32, device="cpu")
            wp.launch(face_displacement, dim=self.dim, inputs=[c, axis, df], device="cpu")
            wp.launch(forward, dim=self.dim, inputs=[s[name], df, hat], device="cpu")
            wp.launch(correct, dim=self.dim, inputs=[s[name], hat, df, out], device="cpu")
            moved[name] = out
        s.update(moved)

    def substep(self, s, dt):
        self.advect(s, dt)
        wp.launch(decay, dim=self.dim, inputs=[s["temperature"], float(np.exp(np.float32(-COOLING * dt)))], device="cpu")
        wp.launch(decay, dim=self.dim, inputs=[s["density"], float(np.exp(np.float32(-DISSIPATION * dt)))], device="cpu")
        wp.launch(buoyancy, dim=self.dim, inputs=[s["v"], s["temperature"], s["density"], dt], device="cpu")
        return self.project(s)


def blob(n):
    """Density and temperature falling linearly from 1 at (N/2, N/4, N/2) to 0 N/6 voxels away."""
    z, y, x = np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij")
    d = np.sqrt((x - n / 2) ** 2 + (y - n / 4) ** 2 + (z - n / 2) ** 2)
    return np.clip(1.0 - d / (n / 6), 0.0, 1.0).astype(np.float32)


def initial(n):
    warm = blob(n)
    a = lambda v: wp.array(v, dtype=wp.float32, device="cpu")
    zero = np.zeros((n, n, n), np.float32)
    return {"density": a(warm), "temperature": a(warm), "u": a(zero), "v": a(zero), "w": a(zero), "pressure": a(zero)}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=128)
    ap.add_argument("--steps", type=int, default=4)
    ap.add_argument("--reps", type=int, default=1)
    ap.add_argument("--warmup", type=int, default=0, help="untimed runs at the full size (kernels compile on a 16³ box first)")
    ap.add_argument("--output")
    a = ap.parse_args()
    wp.init()
    # Compile (or load from Warp's kernel cache) every kernel outside the timed runs.
    small = Solver(16)
    small.substep(initial(16), DT)
    solver = Solver(a.n)
    times, iterations = [], []
    for rep in range(a.warmup + a.reps):
        s = initial(a.n)
        iterations = []
        start = time.perf_counter()
        for _ in range(a.steps):
            iterations.append(solver.substep(s, DT))
        if rep >= a.warmup:
            times.append((time.perf_counter() - start) / a.steps)
    if a.output:
        out = np.stack([s[k].numpy() for k in ("density", "temperature", "u", "v", "w")])
        np.save(a.output, out)
    print(json.dumps({"op": "smoke", "tool": "warp " + wp.__version__, "times_s": times,
                      "median_s": statistics.median(times), "threads": 1, "n": a.n, "steps": a.steps,
                      "iterations": iterations}))


if __name__ == "__main__":
    main()
