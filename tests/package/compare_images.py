"""Do two renderers estimate the same image? Each gives two renders with different seeds;
per 8x8 block, the difference of the renderers' means is compared with its standard error
(estimated from each renderer's own seed-to-seed difference).

    python3 compare_images.py A1.pfm A2.pfm B1.pfm B2.pfm

Passes (exit 0) when every block and the whole image are within 4.5 standard errors: with
48 blocks, two unbiased renderers fail by chance with probability below 1e-3. To show the
test has power, it also requires that A scaled by 0.95 (a 5 % bias) is rejected.
"""

import sys

import numpy as np


def read_pfm(path):
    with open(path, "rb") as file:
        data = file.read()
    header, size, scale, pixels = data.split(b"\n", 3)
    if header != b"PF" or float(scale) >= 0:
        raise SystemExit(f"{path}: not a little-endian colour PFM")
    width, height = map(int, size.split())
    return np.frombuffer(pixels, dtype="<f4").reshape(height, width, 3).astype(np.float64).mean(axis=2)


def worst_z(a1, a2, b1, b2, block=8):
    mean_a, mean_b = (a1 + a2) / 2, (b1 + b2) / 2
    variance = ((a1 - a2) ** 2 + (b1 - b2) ** 2) / 4  # of mean_a - mean_b, per pixel
    worst, where = 0.0, None
    height, width = a1.shape
    parts = [(f"block at ({x}, {y})", (slice(y, y + block), slice(x, x + block)))
             for y in range(0, height, block) for x in range(0, width, block)]
    for name, part in parts + [("whole image", (slice(None), slice(None)))]:
        difference = (mean_a[part] - mean_b[part]).sum()
        error = np.sqrt(variance[part].sum())
        if error == 0:
            z = 0.0 if difference == 0 else np.inf
        else:
            z = abs(difference) / error
        if z > worst:
            worst, where = z, name
    return worst, where


if __name__ == "__main__":
    if len(sys.argv) != 5:
        raise SystemExit(__doc__)
    a1, a2, b1, b2 = (read_pfm(path) for path in sys.argv[1:])
    if a1.shape != b1.shape:
        raise SystemExit(f"sizes differ: {a1.shape} and {b1.shape}")
    z, where = worst_z(a1, a2, b1, b2)
    biased, _ = worst_z(0.95 * a1, 0.95 * a2, b1, b2)
    print(f"images of {a1.shape[1]}x{a1.shape[0]}: mean {a1.mean() / 2 + a2.mean() / 2:.6g} and {b1.mean() / 2 + b2.mean() / 2:.6g}; "
          f"largest difference {z:.2f} standard errors ({where}); a 5 % bias would show {biased:.2f}")
    if z > 4.5:
        raise SystemExit("the two renderers disagree")
    if biased <= 4.5:
        raise SystemExit("the renders are too noisy to tell a 5 % bias apart")
