"""The peers' side of the harness (run.py): the same kernels as `examples/kernels` (pyrograph),
in numpy / OpenCV, reading the same .npy inputs and writing the same outputs for run.py to compare.
Every subcommand runs its kernel `--warmup` times untimed and `--reps` times timed
(time.perf_counter) and prints one JSON line {"op", "tool", "times_s", "median_s", "threads", ...}.

Library calls, per subcommand:
  bloom        ../shared/peers/bloom.py: `bloom` (exact: cv2.GaussianBlur per sigma, ksize 2*round(4s)+1,
               reflect-101, summed, x0.4, np.maximum with the source) or `bloom_pyramid` (each pass on a
               copy shrunk by s//4 with cv2.resize INTER_AREA, GaussianBlur at s/(s//4), cv2.resize back
               INTER_LINEAR); threads: cv2.setNumThreads.
  endgrow      Algorithm 1 of the thesis (§5.1.2.2) in numpy, step for step as pyrograph's
               nodes/eigen/src/transition/end_growing.rs: distance rows by np.einsum over the float32
               weights, candidates by np.argsort (stable, so ties go to the lower frame index).
  reconstruct  eq. 22 batched: W @ U (one float32 OpenBLAS sgemm for all B frames), then += mean in place.
  train        ../shared/peers/pca.py's `gram_eigenfaces` steps (mean, A A^T by BLAS sgemm, np.linalg.eigh,
               lift by A^T V, normalise) on a copy centred in place, and the training weights as
               sqrt(w) V, the identity pyrograph uses: the same result (basis + weights of every
               training frame) from the same work.
  cloth        ../shared/peers/mass_spring.py's model and `add_springs` (numpy, vectorised over all flames),
               with the wind held constant instead of pulsed (both sides integrate the same forces).
  arp          eq. 2 of Stich & Magnor sampled as ../shared/peers/ar_fit.py `sample` does: all noise drawn
               at once (rng.standard_normal @ B^T), then a Python loop of K numpy mat-vecs per step.
"""
import argparse
import json
import os
import sys
import time

import numpy as np

PEERS = os.environ.get("PYROGRAPH_PEERS") or os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../../shared/peers")
sys.path.insert(0, os.path.abspath(PEERS))


def timed(fn, reps, warmup, setup=None):
    """Runs fn `warmup` times, then `reps` times timed; with `setup`, each run gets a fresh
    setup() made outside the timing (as examples/kernels does for kernels that consume input)."""
    call = (lambda: fn(setup())) if setup else fn
    for _ in range(warmup):
        call()
    times, out = [], None
    for _ in range(max(reps, 1)):
        arg = setup() if setup else None
        t0 = time.perf_counter()
        out = fn(arg) if setup else fn()
        times.append(time.perf_counter() - t0)
    return times, out


def report(op, times, threads, **extra):
    print(json.dumps({"op": op, "tool": "peer", "times_s": times, "median_s": float(np.median(times)),
                      "threads": threads, **extra}))


def threads_env():
    """The BLAS / OpenMP thread count in force (what run.py set), or the core count."""
    for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
        if os.environ.get(k):
            return int(os.environ[k])
    return os.cpu_count()


def cmd_bloom(a):
    import cv2
    from bloom import bloom, bloom_pyramid
    if a.threads >= 0:
        cv2.setNumThreads(a.threads)
    src = np.ascontiguousarray(np.load(a.input), np.float32)
    fn = bloom if a.mode == "exact" else bloom_pyramid
    times, out = timed(lambda: fn(src, [32.0, 16.0, 8.0, 4.0], 0.4), a.reps, a.warmup)
    np.save(a.output, out)
    report("bloom", times, cv2.getNumThreads(), mode=a.mode, library="opencv " + cv2.__version__)


# --- End Growing (Algorithm 1) ---------------------------------------------------------------------

def end_growing(X, alpha, beta, max_steps, theta, optimize):
    """Returns (path, shared, steps) as pyrograph's end_growing does (see its doc for the algorithm)."""
    m = len(X)
    rows = {}

    def dist_row(i):
        diff = X - X[i]
        return np.sqrt(np.einsum("ij,ij->i", diff, diff)).astype(np.float64)

    def direct(a, b):
        diff = X[a] - X[b]
        return float(np.sqrt(np.dot(diff, diff)))

    def d(a, b):
        if a in rows:
            return float(rows[a][b])
        if b in rows:
            return float(rows[b][a])
        return direct(a, b)

    def finish(a_path, b_path, steps):
        best = None
        for p, x in enumerate(a_path):
            for q, y in enumerate(b_path):
                shared = x == y
                if not (shared or d(x, y) < theta):
                    continue
                if best is None or p + q < best[0] + best[1]:
                    best = (p, q, shared)
        if best is None:
            return None
        p, q, shared = best
        tail = b_path[1:q] if shared else b_path[1:q + 1]
        path = [f for f in a_path[1:p + 1] + tail[::-1] if f not in (alpha, beta)]
        return path, (a_path[p] if shared else None), steps

    def optimized(r):
        if not optimize:
            return r
        full = [alpha] + r[0] + [beta]
        while True:
            best = None
            for i in range(1, len(full) - 1):
                p, c, n = full[i - 1], full[i], full[i + 1]
                gain = max(direct(p, c), direct(c, n)) - direct(p, n)
                if gain > 0 and (best is None or gain > best[1]):
                    best = (i, gain)
            if best is None:
                break
            del full[best[0]]
        return full[1:-1], r[1], r[2]

    a_path, b_path = [alpha], [beta]
    r = finish(a_path, b_path, 0)
    if r:
        return optimized(r)
    on_a, on_b = np.zeros(m, bool), np.zeros(m, bool)
    on_a[alpha], on_b[beta] = True, True
    for step in range(1, (max_steps + 1) // 2 + 1):
        ca, cb = a_path[-1], b_path[-1]
        for f in (ca, cb):
            if f not in rows:
                rows[f] = dist_row(f)
        big_d = d(ca, cb)

        def candidates(frm, own):
            ds = rows[frm]
            keep = (ds >= theta) & (ds < big_d) & ~own
            keep[alpha] = keep[beta] = False
            idx = np.flatnonzero(keep)
            return idx[np.argsort(ds[idx], kind="stable")]

        la, lb = candidates(ca, on_a), candidates(cb, on_b)
        j = k = 0
        found = False
        while not found and j < len(la) and k < len(lb):
            aj, bk = int(la[j]), int(lb[k])
            if on_b[aj]:
                a_path.append(aj)
                on_a[aj] = found = True
                continue
            if on_a[bk]:
                b_path.append(bk)
                on_b[bk] = found = True
                continue
            if big_d - d(aj, bk) < theta:
                short_to_alpha = d(ca, bk) - big_d <= theta
                short_to_beta = d(cb, aj) - big_d <= theta
                if short_to_alpha and short_to_beta:
                    j, k = j + 1, k + 1
                else:
                    k += not short_to_alpha
                    j += not short_to_beta
            else:
                a_path.append(aj)
                b_path.append(bk)
                on_a[aj] = on_b[bk] = found = True
        if not found:
            raise SystemExit(f"step {step}: no pair of frames brings the ends closer by theta_min")
        r = finish(a_path, b_path, step)
        if r:
            return optimized(r)
    raise SystemExit(f"the two ends did not meet within {max_steps} steps")


def cmd_endgrow(a):
    X = np.ascontiguousarray(np.load(a.weights), np.float32)
    if a.components:
        X = np.ascontiguousarray(X[:, :a.components])
    times, (path, shared, steps) = timed(
        lambda: end_growing(X, a.alpha, a.beta, a.max_steps, a.theta, a.optimize), a.reps, a.warmup)
    with open(a.output, "w") as f:
        json.dump({"path": [int(p) for p in path], "shared": shared, "steps": steps}, f)
    report("endgrow", times, 1, m=len(X), e=X.shape[1], steps=steps, path_len=len(path))


def cmd_reconstruct(a):
    mean = np.load(a.mean).astype(np.float32)
    U = np.ascontiguousarray(np.load(a.basis), np.float32)
    W = np.ascontiguousarray(np.load(a.weights), np.float32)
    def run():
        out = W @ U
        out += mean                                # in place, as pyrograph adds into its output
        return out

    times, out = timed(run, a.reps, a.warmup)
    np.save(a.output, out)
    report("reconstruct", times, threads_env(), batch=len(W), e=U.shape[0], pixels=U.shape[1])


def cmd_train(a):
    frames = np.load(a.frames)
    m = frames.shape[0]
    X = np.ascontiguousarray(frames.reshape(m, -1), np.float32)

    def run(A):
        # pca.py's gram_eigenfaces step for step, centring its own copy in place as pyrograph
        # does, and the training weights from the decomposition, w_l(n) = sqrt(mu_l) v_l(n) --
        # the identity pyrograph uses -- instead of a second product X @ U.
        mean = A.mean(axis=0)
        A -= mean
        L = A @ A.T
        w, V = np.linalg.eigh(L)
        top = np.argsort(w)[::-1][:a.components]
        w, V = w[top], V[:, top]
        U = A.T @ V
        U /= np.linalg.norm(U, axis=0)
        return U, V * np.sqrt(np.maximum(w, 0)), w

    times, (U, weights, w) = timed(run, a.reps, a.warmup, setup=X.copy)
    # Eigenvalues of the covariance as pyrograph reports them (eq. 13): the Gram matrix's over M.
    np.save(a.output_prefix + "eigenvalues.npy", w.astype(np.float64) / m)
    np.save(a.output_prefix + "vectors.npy", np.ascontiguousarray(U[:, :a.keep_vectors].T))
    np.save(a.output_prefix + "weights.npy", np.ascontiguousarray(weights, np.float32))
    report("train", times, threads_env(), frames=m, e=U.shape[1])


def cmd_cloth(a):
    import mass_spring as ms
    x, v, _ = ms.init(a.flames, 16, 32, 0)
    rest = x.copy()

    def step(x, v):
        F = -ms.DRAG * v
        F[1] += ms.BUOYANCY
        F[0] += ms.WIND                            # the wind held on (pyrograph: wind_off 0, no jitter)
        ms.add_springs(F, x, v, 2)
        ms.add_springs(F, x, v, 3)
        v += (ms.DT / ms.MASS) * F
        v[:, :, 0] = 0                             # bottom row pinned
        x += ms.DT * v

    def run():
        xs, vs = rest.copy(), np.zeros_like(v)
        for _ in range(a.steps):
            step(xs, vs)
        return xs

    times, x = timed(run, a.reps, a.warmup)
    moved = np.moveaxis(x - rest, 0, -1)           # (N, rows, cols, 2)
    np.save(a.output, np.ascontiguousarray(moved, np.float32))
    report("cloth_step", [t / a.steps for t in times], 1, flames=a.flames, steps_per_run=a.steps)


def cmd_arp(a):
    A = np.load(os.path.join(a.model_dir, "a.npy"))
    dvec, B = np.load(os.path.join(a.model_dir, "d.npy")), np.load(os.path.join(a.model_dir, "b.npy"))
    offset, scale = np.load(os.path.join(a.model_dir, "offset.npy")), np.load(os.path.join(a.model_dir, "scale.npy"))
    initial = np.load(os.path.join(a.model_dir, "initial.npy"))
    K, D = A.shape[0], A.shape[1]
    rng = np.random.default_rng(a.seed)

    def run():
        hist = [(initial[K - 1 - lag] - offset) / scale for lag in range(K)]   # x_{t-1}, ..., x_{t-K}
        eps = rng.standard_normal((a.steps, D)) @ B.T
        out = np.empty((a.steps, D))
        for t in range(a.steps):
            x = dvec + eps[t]
            for k in range(K):
                x += A[k] @ hist[k]
            hist = [x] + hist[:-1]
            out[t] = x
        return offset + scale * out

    times, out = timed(run, a.reps, a.warmup)
    np.save(a.output, out)
    report("arp_sample", [t / a.steps for t in times], 1, dim=D, order=K, steps_per_run=a.steps)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--warmup", type=int, default=1)
    p.add_argument("--reps", type=int, default=5)
    sub = p.add_subparsers(dest="op", required=True)
    s = sub.add_parser("bloom")
    s.add_argument("--input", required=True)
    s.add_argument("--output", required=True)
    s.add_argument("--mode", choices=["exact", "pyramid"], default="pyramid")
    s.add_argument("--threads", type=int, default=-1)
    s = sub.add_parser("endgrow")
    for k in ("--weights", "--output"):
        s.add_argument(k, required=True)
    for k in ("--alpha", "--beta", "--max-steps"):
        s.add_argument(k, type=int, required=True)
    s.add_argument("--components", type=int, default=0)
    s.add_argument("--theta", type=float, required=True)
    s.add_argument("--optimize", action="store_true")
    s = sub.add_parser("reconstruct")
    for k in ("--mean", "--basis", "--weights", "--output"):
        s.add_argument(k, required=True)
    s = sub.add_parser("train")
    s.add_argument("--frames", required=True)
    s.add_argument("--components", type=int, required=True)
    s.add_argument("--keep-vectors", type=int, default=20)
    s.add_argument("--output-prefix", required=True)
    s = sub.add_parser("cloth")
    s.add_argument("--flames", type=int, required=True)
    s.add_argument("--steps", type=int, required=True)
    s.add_argument("--output", required=True)
    s = sub.add_parser("arp")
    s.add_argument("--model-dir", required=True)
    s.add_argument("--steps", type=int, required=True)
    s.add_argument("--output", required=True)
    s.add_argument("--seed", type=int, default=7)
    a = p.parse_args()
    {"bloom": cmd_bloom, "endgrow": cmd_endgrow, "reconstruct": cmd_reconstruct, "train": cmd_train,
     "cloth": cmd_cloth, "arp": cmd_arp}[a.op](a)


if __name__ == "__main__":
    main()
