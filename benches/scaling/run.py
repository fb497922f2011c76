"""How cost grows with the work (issue 45): time and peak memory against size for particle flames
(100 → 10,000 flames, simulate + render 1280×720), cloth flames (16 → 1,024, a 24 fps frame's
sub-steps + render), fire spread (a plane of 242 → 247,808 faces: the surface built, then 96 steps)
and batch reconstruction (eq. 22, 8 → 256 frames), each size a separate process
of the harness's kernels (examples/kernels) under /usr/bin/time, so that peak RSS is that size's own.
Fits the growth exponent k of time ∝ size^k over the three largest sizes (where the fixed cost of a
1280×720 frame no longer dominates) and plots both against size on log-log axes.

    cargo build --release --example kernels
    python benches/scaling/run.py [--work DIR] [--plot docs/images/scaling.png]   # numpy, matplotlib

Writes --work/scaling.jsonl (one line per size) and the plot; prints a Markdown table for BENCHMARKS.md.
"""
import argparse
import datetime
import json
import os
import platform
import re
import subprocess

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "../.."))
KERNELS = os.path.join(REPO, "target/release/examples/kernels")

# Reconstruction's frame size and basis: the training row's 205×335 frames, E 250.
RECON_P, RECON_E = 205 * 335, 250


def timed(args):
    """Runs the kernels with `args` under /usr/bin/time -v: (its JSON report, peak RSS in MiB)."""
    out = subprocess.run(["/usr/bin/time", "-v", KERNELS, *args], capture_output=True, text=True, check=True)
    report = json.loads(out.stdout.strip().splitlines()[-1])
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", out.stderr)
    return report, int(rss.group(1)) / 1024.0


def recon_inputs(work, frames):
    """Seeded mean, basis and weights for `frames` reconstructed frames (the basis made once)."""
    rng = np.random.default_rng(45)
    paths = {k: os.path.join(work, f"recon_{k}.npy") for k in ("mean", "basis")}
    if not os.path.exists(paths["basis"]):
        np.save(paths["mean"], rng.random(RECON_P, dtype=np.float32))
        basis = rng.standard_normal((RECON_E, RECON_P), dtype=np.float32) / np.float32(np.sqrt(RECON_P))
        np.save(paths["basis"], basis.astype(np.float32))
    weights = os.path.join(work, f"recon_weights_{frames}.npy")
    np.save(weights, rng.standard_normal((frames, RECON_E), dtype=np.float32))
    return ["--mean", paths["mean"], "--basis", paths["basis"], "--weights", weights,
            "--output", os.path.join(work, "recon_out.npy")]


def workloads(work):
    """(name, size label, unit per run, [(size, kernels args)])."""
    particles = [(n, ["--reps", "3", "particles", "--flames", str(n), "--frames", str(f)])
                 for n, f in ((100, 24), (300, 24), (1000, 12), (3000, 6), (10000, 3))]
    cloth = [(n, ["--reps", "3", "cloth-frame", "--flames", str(n), "--frames", str(f)])
             for n, f in ((16, 24), (64, 24), (144, 12), (256, 12), (576, 6), (1024, 3))]
    recon = [(b, ["--reps", "3", "reconstruct", *recon_inputs(work, b)]) for b in (8, 16, 32, 64, 128, 256)]
    spread = [(2 * d * d, ["--reps", "3", "spread", "--divisions", str(d), "--steps", "96"]) for d in (11, 22, 44, 88, 176, 352)]
    return [("particle flames", "flames", "frame", particles),
            ("cloth flames", "flames", "frame", cloth),
            ("fire spread (surface + 96 steps)", "mesh faces", "step", spread),
            ("batch reconstruction", "frames", "batch", recon)]


def growth(sizes, times):
    """The exponent k of time ∝ size^k over the three largest sizes, and its name."""
    k = float(np.polyfit(np.log(sizes[-3:]), np.log(times[-3:]), 1)[0])
    name = "sub-linear" if k < 0.85 else "linear" if k < 1.15 else "n log n or worse" if k < 1.35 else "super-linear"
    return k, name


def plot(results, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(2, len(results), figsize=(3.6 * len(results), 7.0))
    for col, (name, label, unit, rows) in enumerate(results):
        sizes = np.array([r["size"] for r in rows], dtype=float)
        ms = np.array([r["median_s"] * 1e3 for r in rows])
        rss = np.array([r["peak_rss_mib"] for r in rows])
        k, kind = growth(sizes, ms)
        top, bottom = axes[0][col], axes[1][col]
        top.loglog(sizes, ms, "o-", color="#c0392b", label=f"measured (k = {k:.2f}, {kind})")
        ref = ms[-1] * (sizes / sizes[-1])
        top.loglog(sizes, ref, "--", color="#7f8c8d", label="linear through the largest")
        top.set_title(name)
        top.set_ylabel(f"ms per {unit} (median of 3)")
        top.legend(fontsize=8)
        top.grid(True, which="both", alpha=0.3)
        bottom.loglog(sizes, rss, "s-", color="#2c3e50")
        bottom.set_xlabel(label)
        bottom.set_ylabel("peak RSS, MiB (whole process)")
        bottom.grid(True, which="both", alpha=0.3)
    fig.suptitle(f"pyrograph scaling, {platform.node()}, {datetime.date.today()}, 2 threads", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--work", default=os.environ.get("WORK", "/tmp/pyrograph-scaling"))
    p.add_argument("--plot", default=os.path.join(REPO, "docs/images/scaling.png"))
    a = p.parse_args()
    if not os.access(KERNELS, os.X_OK):
        raise SystemExit(f"build first: cargo build --release --example kernels (no {KERNELS})")
    os.makedirs(a.work, exist_ok=True)
    results = []
    with open(os.path.join(a.work, "scaling.jsonl"), "a") as log:
        for name, label, unit, sizes in workloads(a.work):
            rows = []
            for size, args in sizes:
                report, rss = timed(args)
                row = {"workload": name, "size": size, "median_s": report["median_s"], "times_s": report["times_s"],
                       "threads": report["threads"], "peak_rss_mib": round(rss, 1),
                       "when": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
                       "load": os.getloadavg()[0]}
                log.write(json.dumps(row) + "\n")
                print(f"  {name} {size}: {report['median_s'] * 1e3:.2f} ms, {rss:.0f} MiB", flush=True)
                rows.append(row)
            results.append((name, label, unit, rows))
    plot(results, a.plot)
    print(f"\nplot: {a.plot}\n")
    print("| workload | sizes | ms at each size | peak RSS, MiB | growth over the three largest |")
    print("| --- | --- | --- | --- | --- |")
    for name, label, unit, rows in results:
        sizes = [r["size"] for r in rows]
        ms = [r["median_s"] * 1e3 for r in rows]
        k, kind = growth(np.array(sizes, dtype=float), np.array(ms))
        size_text = ", ".join(f"{s:,}" for s in sizes)
        ms_text = ", ".join(f"{m:.3g}" for m in ms)
        rss_text = ", ".join(f"{r['peak_rss_mib']:.0f}" for r in rows)
        print(f"| {name}, per {unit} | {size_text} {label} | {ms_text} | {rss_text} | k = {k:.2f} ({kind}) |")


if __name__ == "__main__":
    main()
