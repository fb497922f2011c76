"""Principal angles between the first K eigenfires of two Eigenfires databases (folders written by
eigen.save_database): the largest angle, in radians, and the mean images' largest difference.

    python angles.py DB_A DB_B [K]

Reads `mean.bin` and `pack_001.bin` (the first pack holds the first `pack_size` eigenfires, N
little-endian f32 each); N and M come from each `database.ron` header.
"""
import os
import re
import sys

import numpy as np


def header(db):
    text = open(os.path.join(db, "database.ron")).read()
    field = lambda name: int(re.search(rf"\b{name}:\s*(\d+)", text).group(1))
    return field("width") * field("height")


def eigenfires(db, k):
    n = header(db)
    u = np.fromfile(os.path.join(db, "pack_001.bin"), dtype="<f4", count=k * n)
    if u.size != k * n:
        sys.exit(f"{db}: its first pack holds fewer than {k} eigenfires")
    return u.reshape(k, n).T.astype(np.float64), np.fromfile(os.path.join(db, "mean.bin"), dtype="<f4")


def main():
    a, b = sys.argv[1], sys.argv[2]
    k = int(sys.argv[3]) if len(sys.argv) > 3 else 50
    (ua, ma), (ub, mb) = eigenfires(a, k), eigenfires(b, k)
    qa, _ = np.linalg.qr(ua)
    qb, _ = np.linalg.qr(ub)
    s = np.linalg.svd(qa.T @ qb, compute_uv=False)
    angles = np.arccos(np.clip(s, -1.0, 1.0))
    # Eigenfire by eigenfire (same order and sign convention on both sides).
    cos = np.abs(np.sum(ua * ub, axis=0)) / (np.linalg.norm(ua, axis=0) * np.linalg.norm(ub, axis=0))
    print(f"first {k} eigenfires: largest principal angle {angles.max():.3e} rad; "
          f"eigenfire by eigenfire, smallest |cos| {cos.min():.9f} (component {int(cos.argmin())}); "
          f"mean images differ by at most {np.abs(ma - mb).max():.3e}")
    if angles.max() >= 1e-3:
        sys.exit("principal angle of 1e-3 or more")


if __name__ == "__main__":
    main()
