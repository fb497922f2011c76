"""Renders mitsuba_reference.rs's scenes with Mitsuba 3 and compares them with pyrograph's.

Usage: mitsuba_check.py DIR --spp N [--pictures OUT_DIR]

DIR holds scenes.json (camera, box, extinction, albedo, anisotropy, lights per scene) and, per
scene k, k.density.f32 (n³ little-endian floats, x fastest, voxel centres at the cell centres of
the box), k.pyrograph.f32 (height × width × RGBA, premultiplied over black) and k.octaves.f32
(the same with volume.render's multiple-scattering octaves, set against all orders). Each scene is
rendered twice with the volumetric path tracer (`volpath`, scalar_rgb): single scattering
(max_depth 2, what pyrograph computes) and all orders (max_depth −1). The metrics, on the pixels
where pyrograph's smoke covers at least 2 % (its "smoke pixels"), on linear RGB clamped to [0, 1]:
mean absolute error and SSIM (scikit-image, 7-pixel window, the map averaged over those pixels).
Prints JSON after a marker line.
"""

import argparse
import json
import sys
import time
from pathlib import Path

import mitsuba as mi
import numpy as np
from skimage.metrics import structural_similarity

MARKER = "== mitsuba_check json"
mi.set_variant("scalar_rgb")
T = mi.ScalarTransform4f


def scene_dict(s, density, max_depth, spp):
    lo, hi = np.array(s["box"][0]), np.array(s["box"][1])
    grid = mi.VolumeGrid(density[..., None].astype(np.float32))
    medium = {
        "type": "heterogeneous",
        "albedo": s["albedo"],
        "scale": s["extinction"],
        "sigma_t": {
            "type": "gridvolume",
            "grid": grid,
            "filter_type": "trilinear",
            # gridvolume spans the unit cube with its values at the cells' centres, as
            # pyrograph's voxels are centred in the box's cells.
            "to_world": T().translate(lo.tolist()).scale((hi - lo).tolist()),
        },
        "phase": {"type": "hg", "g": s["anisotropy"]},
    }
    d = {
        "type": "scene",
        "integrator": {"type": "volpath", "max_depth": max_depth},
        "sensor": {
            "type": "perspective",
            "fov": s["fov"],
            "fov_axis": "y",
            "near_clip": 0.01,
            "to_world": T().look_at(origin=s["eye"], target=s["target"], up=s["up"]),
            "film": {
                "type": "hdrfilm",
                "width": s["width"],
                "height": s["height"],
                "pixel_format": "rgba",
                "rfilter": {"type": "box"},
            },
            "sampler": {"type": "independent", "sample_count": spp},
        },
        "box": {
            "type": "cube",
            "to_world": T().translate(((lo + hi) / 2).tolist()).scale(((hi - lo) / 2).tolist()),
            "bsdf": {"type": "null"},
            "interior": medium,
        },
        "sun": {
            "type": "directional",
            # Mitsuba's direction is the light's travel; pyrograph's points toward the sun.
            "direction": [-x for x in s["sun"]],
            "irradiance": {"type": "rgb", "value": [s["sun_irradiance"]] * 3},
        },
    }
    if s.get("point"):
        d["point"] = {
            "type": "point",
            "position": s["point"]["at"],
            "intensity": {"type": "rgb", "value": [s["point"]["intensity"]] * 3},
        }
    return d


def render(s, density, max_depth, spp):
    scene = mi.load_dict(scene_dict(s, density, max_depth, spp))
    img = np.array(mi.render(scene, seed=s["index"] * 2 + (max_depth > 0)))
    return img[..., :3]


def metrics(ours, theirs, mask):
    a, b = np.clip(ours, 0, 1), np.clip(theirs, 0, 1)
    mae = float(np.abs(a - b)[mask].mean())
    _, ssim_map = structural_similarity(a, b, channel_axis=2, data_range=1.0, win_size=7, full=True)
    return mae, float(ssim_map.mean(axis=2)[mask].mean())


def srgb(x):
    x = np.clip(x, 0, 1)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def picture(rows, path):
    from PIL import Image

    tiles = [np.concatenate(r, axis=1) for r in rows]
    img = np.concatenate(tiles, axis=0)
    Image.fromarray((srgb(img) * 255 + 0.5).astype(np.uint8)).save(path)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dir", type=Path)
    ap.add_argument("--spp", type=int, default=512)
    ap.add_argument("--pictures", type=Path)
    args = ap.parse_args()
    scenes = json.loads((args.dir / "scenes.json").read_text())
    results, rows = [], []
    for s in scenes:
        n, w, h, k = s["n"], s["width"], s["height"], s["index"]
        density = np.fromfile(args.dir / f"{k}.density.f32", dtype="<f4").reshape(n, n, n)
        ours = np.fromfile(args.dir / f"{k}.pyrograph.f32", dtype="<f4").reshape(h, w, 4)
        started = time.perf_counter()
        single = render(s, density, 2, args.spp)
        middle = time.perf_counter()
        full = render(s, density, -1, args.spp)
        done = time.perf_counter()
        mask = ours[..., 3] > 0.02
        mae_s, ssim_s = metrics(ours[..., :3], single, mask)
        mae_f, ssim_f = metrics(ours[..., :3], full, mask)
        octaves = np.fromfile(args.dir / f"{k}.octaves.f32", dtype="<f4").reshape(h, w, 4)
        mae_o, ssim_o = metrics(octaves[..., :3], full, mask)
        gain = float(full[mask].sum() / max(single[mask].sum(), 1e-12) - 1.0)
        results.append(
            {
                "name": s["name"],
                "mask_pixels": int(mask.sum()),
                "mae_single": mae_s,
                "ssim_single": ssim_s,
                "mae_full": mae_f,
                "ssim_full": ssim_f,
                "mae_octaves": mae_o,
                "ssim_octaves": ssim_o,
                "mean_octaves": float(octaves[..., :3][mask].mean()),
                "multiple_gain": gain,
                "mean_pyrograph": float(ours[..., :3][mask].mean()),
                "mean_single": float(single[mask].mean()),
                "mean_full": float(full[mask].mean()),
                "mitsuba_seconds_single": middle - started,
                "mitsuba_seconds_full": done - middle,
                "pyrograph_seconds": s["pyrograph_seconds"],
                "spp": args.spp,
            }
        )
        diff = np.abs(np.clip(ours[..., :3], 0, 1) - np.clip(single, 0, 1)) * 4
        rows.append([ours[..., :3], single, octaves[..., :3], full, diff])
        print(f"{s['name']}: MAE {mae_s:.4f} SSIM {ssim_s:.3f} (all orders {mae_f:.4f} {ssim_f:.3f}; octaves {mae_o:.4f} {ssim_o:.3f})", file=sys.stderr)
    if args.pictures:
        args.pictures.mkdir(parents=True, exist_ok=True)
        picture(rows, args.pictures / "volume-mitsuba.png")
    print(MARKER)
    print(json.dumps(results))


if __name__ == "__main__":
    main()
