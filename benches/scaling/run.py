"""How cost grows with the work (issue 45): time and peak memory against size for particle flames
(100 → 10,000 flames, simulate + render 1280×720), cloth flames (16 → 1,024, a 24 fps frame's
sub-steps + render), fire spread (a plane of 242 → 247,808 faces: the surface built, then 96 steps),
batch reconstruction (eq. 22, 8 → 256 frames), the smoke solver's sub-step against active voxels
(volume.simulate's step on a dense box of warm smoke, 24³ → 216³: 1.4·10⁴ → 10⁷ voxels, every brick
active) and the mask chain against resolution (480p → 4K: the
peer harness's benches/maskchain/mask.ron rendered by the CLI over 48 PNG frames, read to written),
each size a separate process of the harness's kernels (examples/kernels) or of the CLI under
/usr/bin/time, so that peak RSS is that size's own.
Fits the growth exponent k of time ∝ size^k over the three largest sizes (where the fixed cost of a
1280×720 frame no longer dominates) and plots both against size on log-log axes.

    cargo build --release --example kernels && cargo build --release
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
CLI = os.path.join(REPO, "target/release/pyrograph")
FOOTAGE = os.environ.get("PYROGRAPH_FOOTAGE") or os.path.join(REPO, "../shared/footage")

# The mask chain's sizes: 16:9 frames from 480p to 4K, 48 frames each (the candle-black clip scaled).
MASK_SIZES = [(854, 480), (1280, 720), (1920, 1080), (2560, 1440), (3840, 2160)]
MASK_FRAMES = 48

# Reconstruction's frame size and basis: the training row's 205×335 frames, E 250.
RECON_P, RECON_E = 205 * 335, 250


def timed(args):
    """Runs the kernels with `args` under /usr/bin/time -v: (its JSON report, peak RSS in MiB)."""
    out = subprocess.run(["/usr/bin/time", "-v", KERNELS, *args], capture_output=True, text=True, check=True)
    report = json.loads(out.stdout.strip().splitlines()[-1])
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", out.stderr)
    return report, int(rss.group(1)) / 1024.0


def mask_chain(work, size, reps=3):
    """The CLI renders mask.ron over MASK_FRAMES frames of `size` (made once by ffmpeg), `reps`
    times after one untimed run: (a report like the kernels' with seconds per frame, peak RSS MiB)."""
    w, h = size
    frames = os.path.join(work, f"candle_{w}x{h}_{MASK_FRAMES}")
    if not os.path.isdir(frames):
        candle = os.path.join(FOOTAGE, "candle-black/candle_flame.mp4")
        if not os.path.exists(candle):
            raise SystemExit(f"no footage at {candle}: set PYROGRAPH_FOOTAGE")
        os.makedirs(frames + ".part", exist_ok=True)
        subprocess.run(["ffmpeg", "-v", "error", "-nostdin", "-y", "-stream_loop", "-1", "-i", candle, "-an",
                        "-vf", f"scale={w}:{h}:flags=bicubic", "-frames:v", str(MASK_FRAMES), "-start_number", "0",
                        os.path.join(frames + ".part", "f_%04d.png")], check=True)
        os.replace(frames + ".part", frames)
    out = os.path.join(work, "mask_out")
    cmd = ["/usr/bin/time", "-f", "%e %M", CLI, "render", os.path.join(REPO, "benches/maskchain/mask.ron"),
           "--out", out, "--set", f'load.path="{frames}"', "--set", 'write.pattern="mask_####.png"']
    times, rss = [], []
    for i in range(reps + 1):
        r = subprocess.run(cmd, capture_output=True, text=True, check=True)
        wall, kb = r.stderr.strip().splitlines()[-1].split()
        if i > 0:
            times.append(float(wall) / MASK_FRAMES)
            rss.append(int(kb) / 1024.0)
    written = len([f for f in os.listdir(out) if f.startswith("mask_")])
    if written != MASK_FRAMES:
        raise SystemExit(f"mask chain at {w}x{h} wrote {written} masks, want {MASK_FRAMES}")
    threads = int(os.environ.get("RAYON_NUM_THREADS", os.cpu_count()))
    return {"times_s": times, "median_s": float(np.median(times)), "threads": threads}, float(np.median(rss))


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
    smoke = [(n ** 3, ["--warmup", "0", "--reps", "3" if n <= 96 else "1", "smoke", "--n", str(n), "--steps", str(steps)])
             for n, steps in ((24, 8), (48, 8), (96, 4), (136, 2), (216, 2))]
    masks = [(w * h, ("mask", (w, h))) for w, h in MASK_SIZES]
    return [("particle flames", "flames", "frame", particles),
            ("cloth flames", "flames", "frame", cloth),
            ("fire spread (surface + 96 steps)", "mesh faces", "step", spread),
            ("batch reconstruction", "frames", "batch", recon),
            ("smoke solver sub-step", "active voxels", "sub-step", smoke),
            ("mask chain, 480p to 4K", "pixels a frame", "frame", masks)]


def growth(sizes, times):
    """The exponent k of time ∝ size^k over the three largest sizes, and its name."""
    k = float(np.polyfit(np.log(sizes[-3:]), np.log(times[-3:]), 1)[0])
    name = "sub-linear" if k < 0.85 else "linear" if k < 1.15 else "n log n or worse" if k < 1.35 else "super-linear"
    return k, name


def plot(results, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter
    fig, axes = plt.subplots(2, len(results), figsize=(3.4 * len(results), 7.0), squeeze=False)
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
        for ax in (top, bottom):
            # Within about a decade matplotlib labels minor ticks too, and they run into each other.
            ax.xaxis.set_minor_formatter(NullFormatter())
    fig.suptitle(f"pyrograph scaling, {platform.node()}, {datetime.date.today()}, 2 threads", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--work", default=os.environ.get("WORK", "/tmp/pyrograph-scaling"))
    p.add_argument("--plot", default=os.path.join(REPO, "docs/images/scaling.png"))
    p.add_argument("--only", default="", help="comma-separated words of workload names to measure (e.g. smoke); "
                                               "the plot then holds only those")
    p.add_argument("--from", dest="rows", metavar="JSONL",
                   help="plot and tabulate a previous run's scaling.jsonl (its latest row of each size) instead of running")
    a = p.parse_args()
    results = replay(a.rows) if a.rows else measure(a.work, [w for w in a.only.split(",") if w])
    plot(results, a.plot)
    print(f"\nplot: {a.plot}\n")
    table(results)


def measure(work, only=()):
    """Runs every workload (or those whose name holds a word of `only`) at every size: [(name, size
    label, unit, rows)], logged to work/scaling.jsonl."""
    for exe in (KERNELS, CLI):
        if not os.access(exe, os.X_OK):
            raise SystemExit(f"build first: cargo build --release --example kernels && cargo build --release (no {exe})")
    os.makedirs(work, exist_ok=True)
    results = []
    with open(os.path.join(work, "scaling.jsonl"), "a") as log:
        for name, label, unit, sizes in workloads(work):
            if only and not any(w in name for w in only):
                continue
            rows = []
            for size, args in sizes:
                got, rss = mask_chain(work, args[1]) if args[0] == "mask" else timed(args)
                row = {"workload": name, "label": label, "unit": unit, "size": size, "median_s": got["median_s"],
                       "times_s": got["times_s"], "threads": got["threads"], "peak_rss_mib": round(rss, 1),
                       "when": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
                       "load": os.getloadavg()[0]}
                log.write(json.dumps(row) + "\n")
                print(f"  {name} {size}: {got['median_s'] * 1e3:.2f} ms, {rss:.0f} MiB", flush=True)
                rows.append(row)
            results.append((name, label, unit, rows))
    return results


def replay(path):
    """A previous run's results from its log: the latest row of each workload and size, in the
    order the workloads first appear."""
    latest, order = {}, []
    with open(path) as f:
        for line in f:
            row = json.loads(line)
            if row["workload"] not in order:
                order.append(row["workload"])
            latest.setdefault(row["workload"], {})[row["size"]] = row
    results = []
    for name in order:
        rows = [latest[name][size] for size in sorted(latest[name])]
        results.append((name, rows[0].get("label", "size"), rows[0].get("unit", "run"), rows))
    return results


def table(results):
    """Prints the Markdown table for BENCHMARKS.md."""
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
