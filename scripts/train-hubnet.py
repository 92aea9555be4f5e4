#!/usr/bin/env python3
"""Train the learned hub heatmap (`libs/detect/src/heat.rs`) on frames `hubtrack dataset` rendered.

The network maps the detector's 192x128 grey network input to one logit per 8x8-pixel cell:
"the rotor's hub lies in this cell". It is trained on the project's own renderer only (never on
`../shared/data`), with augmentations that take away what the renderer gets too easy (the
turbine's shade, the sky's brightness, sharpness, framing): brightness inversion, gamma,
contrast, noise, blur, zoom and mirror. The result is written as ONNX (opset 11, plain
Conv/Relu, which OpenCV 4.6's dnn module reads) for `include_bytes!` in the detector.

With `--model crop` it trains the hub crop network instead (`HubCropNet` in the same file): a
64x64 crop of the working pyramid level around a candidate hub (side `CROP_FRAC` of the frame
height) to one logit per 4x4-pixel cell, which places the hub to a fraction of a spinner radius
where the blade-edge crossings are biased (frames from `hubtrack dataset --working`).

Usage: train-hubnet.py --out libs/detect/models/hubnet.onnx [--model frame|crop] [--epochs N] DATASET_DIR...
(the last directory is held out and reported). `scripts/train-hubnet.sh` is the whole recipe.
"""
import argparse
import json
import os
import sys
import time

import numpy as np

W, H, STRIDE = 192, 128, 8
GW, GH = W // STRIDE, H // STRIDE
# (in, out, stride, dilation) of the 3x3 convolutions; a 1x1 convolution gives the logit.
LAYERS = [(1, 8, 2, 1), (8, 16, 2, 1), (16, 16, 1, 1), (16, 32, 2, 1), (32, 32, 1, 2), (32, 32, 1, 4)]
SIGMA_CELLS = 0.6

# The crop network (keep in step with `heat.rs`: CROP_SIDE, CROP_STRIDE, CROP_FRAC).
CROP_SIDE, CROP_STRIDE = 64, 4
CROP_GRID = CROP_SIDE // CROP_STRIDE
CROP_FRAC = 0.3
CROP_LAYERS = [(1, 8, 2, 1), (8, 16, 1, 1), (16, 32, 2, 1), (32, 32, 1, 2), (32, 32, 1, 4)]
# Training crops are centred this far from the hub at most (fraction of the frame height: the
# candidates the detector refines are a spinner radius or two off), and a quarter of them lie
# elsewhere (no hub in them, or only at the crop's rim) ...
CROP_OFFSET_FRAC = 0.12
CROP_NEGATIVE_SHARE = 0.25
# ... and their side varies by this factor either way (the spinner's size in the crop varies
# with range anyway; this covers lenses and pyramid levels).
CROP_SCALE_JITTER = 0.15


def load(dirs, any_size=False):
    """Frames and hubs (fractions of the frame; -1 without a hub in view). Frames of the frame
    model are stacked (all 192x128); working levels (`any_size`) stay a list."""
    from PIL import Image
    xs, ys = [], []
    for d in dirs:
        for line in open(os.path.join(d, "labels.jsonl")):
            r = json.loads(line)
            img = np.asarray(Image.open(os.path.join(d, r["file"])).convert("L"), dtype=np.uint8)
            assert any_size or img.shape == (H, W), (r["file"], img.shape)
            xs.append(img)
            hub = r["hub"]
            ys.append(hub if hub is not None and 0 <= hub[0] <= 1 and 0 <= hub[1] <= 1 else [-1.0, -1.0])
    return (xs if any_size else np.stack(xs)), np.asarray(ys, dtype=np.float32)


def targets(hubs, gw=GW, gh=GH):
    """Gaussian bumps (peak 1) on the cell grid around each hub; all zero without one."""
    gx = (np.arange(gw) + 0.5) / gw
    gy = (np.arange(gh) + 0.5) / gh
    dx = (gx[None, None, :] - hubs[:, 0, None, None]) * gw
    dy = (gy[None, :, None] - hubs[:, 1, None, None]) * gh
    t = np.exp(-(dx**2 + dy**2) / (2 * SIGMA_CELLS**2))
    t[hubs[:, 0] < 0] = 0.0
    return t.astype(np.float32)


def crop(img, cx, cy, side):
    """The `CROP_SIDE`-square crop of side `side` (px) centred on (cx, cy) px, bilinear, the
    border replicated: what `HubCropNet` cuts with OpenCV's warpAffine (pixel centres mapped as
    x_in = x0 + (u + 0.5)·s - 0.5)."""
    h, w = img.shape
    s = side / CROP_SIDE
    u = cx - side / 2 + (np.arange(CROP_SIDE) + 0.5) * s - 0.5
    v = cy - side / 2 + (np.arange(CROP_SIDE) + 0.5) * s - 0.5
    u, v = np.clip(u, 0, w - 1), np.clip(v, 0, h - 1)
    u0, v0 = np.minimum(u.astype(int), w - 2), np.minimum(v.astype(int), h - 2)
    fu, fv = (u - u0)[None, :], (v - v0)[:, None]
    f = img.astype(np.float32)
    a, b = f[v0][:, u0], f[v0][:, u0 + 1]
    c, d = f[v0 + 1][:, u0], f[v0 + 1][:, u0 + 1]
    return (a * (1 - fu) + b * fu) * (1 - fv) + (c * (1 - fu) + d * fu) * fv


def sample_crops(frames, hubs, idx, rng, negative_share=CROP_NEGATIVE_SHARE):
    """Crops of frames `idx` (uint8 0..255 as float) with the hub as a fraction of the crop
    (-1 when outside it), and per crop (frame height px per crop px, x0, y0) to map back."""
    xs, ys, geo = [], [], []
    for i in idx:
        img = frames[i]
        h, w = img.shape
        side = h * CROP_FRAC * np.exp(rng.uniform(-CROP_SCALE_JITTER, CROP_SCALE_JITTER))
        hub = hubs[i] * [w, h] if hubs[i, 0] >= 0 else None
        if hub is not None and rng.random() >= negative_share:
            r = CROP_OFFSET_FRAC * h * np.sqrt(rng.random())
            a = rng.uniform(0, 2 * np.pi)
            cx, cy = hub[0] + r * np.cos(a), hub[1] + r * np.sin(a)
        else:
            cx, cy = rng.uniform(0, w), rng.uniform(0, h)
        xs.append(crop(img, cx, cy, side))
        x0, y0 = cx - side / 2, cy - side / 2
        if hub is not None:
            fx, fy = (hub[0] - x0) / side, (hub[1] - y0) / side
            ys.append([fx, fy] if 0 <= fx <= 1 and 0 <= fy <= 1 else [-1.0, -1.0])
        else:
            ys.append([-1.0, -1.0])
        geo.append((side, x0, y0, h))
    return np.stack(xs), np.asarray(ys, dtype=np.float32), geo


def augment(x, hubs, rng, zoom=True):
    """Random photometric and geometric changes; returns float images in [0, 1] and hubs."""
    n, H, W = x.shape
    x = x.astype(np.float32) / 255.0
    hubs = hubs.copy()
    if zoom:
        x, hubs = zoom_in(x, hubs, rng)
    return photometric(x, hubs, rng)


def zoom_in(x, hubs, rng):
    """Zoom in (crop and scale back) on part of the batch, nearest-neighbour."""
    n, H, W = x.shape
    out = np.empty_like(x)
    for i in range(n):
        s = rng.uniform(0.7, 1.0) if rng.random() < 0.5 else 1.0
        cw, ch = W * s, H * s
        x0, y0 = rng.uniform(0, W - cw), rng.uniform(0, H - ch)
        xi = np.clip((x0 + (np.arange(W) + 0.5) * s).astype(int), 0, W - 1)
        yi = np.clip((y0 + (np.arange(H) + 0.5) * s).astype(int), 0, H - 1)
        out[i] = x[i][yi][:, xi]
        if hubs[i, 0] >= 0:
            hx, hy = (hubs[i, 0] * W - x0) / cw, (hubs[i, 1] * H - y0) / ch
            hubs[i] = [hx, hy] if 0 <= hx <= 1 and 0 <= hy <= 1 else [-1, -1]
    return out, hubs


def photometric(x, hubs, rng, mirror=True):
    """Mirror, brightness inversion, gamma, contrast, blur, noise and quantisation."""
    n = len(x)
    flip = (rng.random(n) < 0.5) & mirror
    x[flip] = x[flip][:, :, ::-1]
    hubs[flip & (hubs[:, 0] >= 0), 0] = 1.0 - hubs[flip & (hubs[:, 0] >= 0), 0]
    inv = rng.random(n) < 0.35
    x[inv] = 1.0 - x[inv]
    gamma = np.exp(rng.uniform(-0.5, 0.5, n)).astype(np.float32)
    x = np.clip(x, 1e-4, 1.0) ** gamma[:, None, None]
    c = rng.uniform(0.5, 1.3, n).astype(np.float32)
    b = rng.uniform(-0.15, 0.15, n).astype(np.float32)
    m = x.mean(axis=(1, 2), keepdims=True)
    x = (x - m) * c[:, None, None] + m + b[:, None, None]
    blur = rng.random(n) < 0.3
    if blur.any():
        y = x[blur]
        y = (y + np.roll(y, 1, 1) + np.roll(y, -1, 1)) / 3
        y = (y + np.roll(y, 1, 2) + np.roll(y, -1, 2)) / 3
        x[blur] = y
    x = x + rng.normal(0, 1, x.shape).astype(np.float32) * rng.uniform(0, 0.04, n).astype(np.float32)[:, None, None]
    # Quantise as a camera would.
    x = np.round(np.clip(x, 0, 1) * 255) / 255
    return x.astype(np.float32), hubs


def init(rng, layers=LAYERS):
    params = []
    for cin, cout, _, _ in layers:
        w = rng.normal(0, np.sqrt(2.0 / (cin * 9)), (cout, cin, 3, 3)).astype(np.float32)
        params.append((w, np.zeros(cout, np.float32)))
    cin = layers[-1][1]
    params.append((rng.normal(0, np.sqrt(1.0 / cin), (1, cin, 1, 1)).astype(np.float32), np.full(1, -4.0, np.float32)))
    return params


def forward(params, x, layers=LAYERS):
    import jax
    from jax import lax
    h = x[:, None]
    for (w, b), (_, _, s, d) in zip(params[:-1], layers):
        h = lax.conv_general_dilated(h, w, (s, s), [(d, d), (d, d)], rhs_dilation=(d, d), dimension_numbers=("NCHW", "OIHW", "NCHW"))
        h = jax.nn.relu(h + b[None, :, None, None])
    w, b = params[-1]
    h = lax.conv_general_dilated(h, w, (1, 1), [(0, 0), (0, 0)], dimension_numbers=("NCHW", "OIHW", "NCHW"))
    return h[:, 0] + b[0]


def loss_fn(params, x, t, layers=LAYERS):
    import jax.numpy as jnp
    z = forward(params, x, layers)
    # Binary cross-entropy on soft targets; the few hub cells weigh like the many others.
    bce = jnp.maximum(z, 0) - z * t + jnp.log1p(jnp.exp(-jnp.abs(z)))
    return jnp.mean(bce * (1.0 + 40.0 * t))


def evaluate(params, x, hubs, fwd):
    """Per frame: peak probability and whether the peak cell is within one cell of the hub."""
    probs = []
    for i in range(0, len(x), 256):
        z = np.asarray(fwd(params, x[i:i + 256].astype(np.float32) / 255.0))
        probs.append(1 / (1 + np.exp(-z)))
    p = np.concatenate(probs)
    flat = p.reshape(len(p), -1)
    k = flat.argmax(1)
    peak = flat.max(1)
    cx, cy = (k % GW + 0.5) / GW, (k // GW + 0.5) / GH
    pos = hubs[:, 0] >= 0
    near = (np.abs(cx - hubs[:, 0]) * GW <= 1.0) & (np.abs(cy - hubs[:, 1]) * GH <= 1.0)
    return {
        "frames_with_hub": int(pos.sum()),
        "peak_within_1_cell_%": round(100 * float(near[pos].mean()), 1),
        "peak_p_median_hub": round(float(np.median(peak[pos])), 3),
        "peak_p_median_no_hub": round(float(np.median(peak[~pos])), 3) if (~pos).any() else None,
        "no_hub_peak_over_0.5_%": round(100 * float((peak[~pos] > 0.5).mean()), 1) if (~pos).any() else None,
    }


def crop_peak(p):
    """Per crop map (n, g, g): the most probable cell's probability and the hub as a fraction of
    the crop, the probability-weighted mean of the cell centres in its 3x3 neighbourhood (as
    `Heatmap::peak` in heat.rs)."""
    n, g, _ = p.shape
    flat = p.reshape(n, -1)
    k = flat.argmax(1)
    ky, kx = k // g, k % g
    pos = np.zeros((n, 2))
    for i in range(n):
        y0, y1, x0, x1 = max(ky[i] - 1, 0), min(ky[i] + 2, g), max(kx[i] - 1, 0), min(kx[i] + 2, g)
        w = p[i, y0:y1, x0:x1]
        yy, xx = np.mgrid[y0:y1, x0:x1]
        pos[i] = [((xx + 0.5) * w).sum() / w.sum() / g, ((yy + 0.5) * w).sum() / w.sum() / g]
    return flat.max(1), pos


def evaluate_crops(params, frames, hubs, fwd):
    """Held-out crops (a fixed draw): how often the peak lies within 3 % of the frame height of
    the hub, and the peak probabilities with and without a hub in the crop."""
    rng = np.random.default_rng(12345)
    idx = rng.integers(0, len(frames), 4000)
    x, ys, geo = sample_crops(frames, hubs, idx, rng)
    z = np.concatenate([np.asarray(fwd(params, x[i:i + 256] / 255.0)) for i in range(0, len(x), 256)])
    peak, pos = crop_peak(1 / (1 + np.exp(-z)))
    has = ys[:, 0] >= 0
    err = np.array([np.hypot(*(pos[i] - ys[i])) * geo[i][0] / geo[i][3] * 100 for i in range(len(x))])
    near = has & (err <= 3.0)
    return {
        "crops_with_hub": int(has.sum()),
        "peak_within_3%h_%": round(100 * float(near[has].mean()), 1),
        "median_error_%h": round(float(np.median(err[has])), 2),
        "peak_p_median_hub": round(float(np.median(peak[has])), 3),
        "peak_p_median_no_hub": round(float(np.median(peak[~has])), 3),
        "no_hub_peak_over_0.5_%": round(100 * float((peak[~has] > 0.5).mean()), 1),
    }


# The yaw network (keep in step with `heat.rs`: YAW_SIDE, YAW_WINDOW_M, YAW_BINS, YAW_MAX_DEG).
YAW_SIDE = 64
YAW_WINDOW_M = 8.0
YAW_MAX_DEG = 40.0
YAW_BINS = 33
YAW_CENTRES = np.linspace(-YAW_MAX_DEG, YAW_MAX_DEG, YAW_BINS)
# (in, out, stride, dilation) of the 3x3 convolutions down to 8x8; then an 8x8 convolution to
# YAW_HIDDEN features (a fully connected layer written as a convolution) and a 1x1 to the bins.
YAW_LAYERS = [(1, 16, 2, 1), (16, 32, 2, 1), (32, 32, 1, 1), (32, 48, 2, 1), (48, 48, 1, 1)]
YAW_HIDDEN = 96
# Soft targets: a Gaussian of this width over the bins, degrees.
YAW_LABEL_SIGMA_DEG = 2.0
# Training crops: the hub misplaced by this much (normal, fraction of the frame height), the
# distance that scales the window wrong by this much (log-normal), frames within these distances.
YAW_HUB_JITTER_FRAC = 0.015
YAW_DISTANCE_JITTER = 0.1
YAW_DISTANCE_RANGE_M = (3.5, 46.0)


def load_yaw(dirs):
    """Working levels with a hub in view within `YAW_DISTANCE_RANGE_M`, and per frame (hub x, hub
    y as fractions, distance m, relative yaw deg, focal length per width)."""
    from PIL import Image
    xs, ys = [], []
    for d in dirs:
        for line in open(os.path.join(d, "labels.jsonl")):
            r = json.loads(line)
            hub = r["hub"]
            if hub is None or not (0 <= hub[0] <= 1 and 0 <= hub[1] <= 1):
                continue
            if not YAW_DISTANCE_RANGE_M[0] <= r["distance_m"] <= YAW_DISTANCE_RANGE_M[1]:
                continue
            xs.append(np.asarray(Image.open(os.path.join(d, r["file"])).convert("L"), dtype=np.uint8))
            ys.append([hub[0], hub[1], r["distance_m"], r["relative_yaw_deg"], r["focal_per_width"]])
    return xs, np.asarray(ys, dtype=np.float64)


def sample_yaw_crops(frames, labels, idx, rng, jitter=True):
    """Crops (`YAW_SIDE` square, `YAW_WINDOW_M` wide at the hub's distance) around the hub of
    frames `idx`, mirrored at random, and their relative yaws (degrees, negated when mirrored)."""
    xs, yaws = [], []
    for i in idx:
        img = frames[i]
        h, w = img.shape
        hx, hy, dist, yaw, fpw = labels[i]
        d = dist * (np.exp(rng.normal(0, YAW_DISTANCE_JITTER)) if jitter else 1.0)
        side = fpw * w * YAW_WINDOW_M / d
        j = rng.normal(0, YAW_HUB_JITTER_FRAC * h, 2) if jitter else np.zeros(2)
        c = crop(img, hx * w + j[0], hy * h + j[1], side)
        if jitter and rng.random() < 0.5:
            c, yaw = c[:, ::-1], -yaw
        xs.append(c)
        yaws.append(yaw)
    return np.stack(xs), np.asarray(yaws)


def yaw_targets(yaws):
    """Soft bin targets (rows sum to 1)."""
    t = np.exp(-0.5 * ((YAW_CENTRES[None, :] - np.clip(yaws, -YAW_MAX_DEG, YAW_MAX_DEG)[:, None]) / YAW_LABEL_SIGMA_DEG) ** 2)
    return (t / t.sum(1, keepdims=True)).astype(np.float32)


def init_yaw(rng):
    params = init(rng, YAW_LAYERS)[:-1]
    cin = YAW_LAYERS[-1][1]
    params.append((rng.normal(0, np.sqrt(2.0 / (cin * 64)), (YAW_HIDDEN, cin, 8, 8)).astype(np.float32), np.zeros(YAW_HIDDEN, np.float32)))
    params.append((rng.normal(0, np.sqrt(1.0 / YAW_HIDDEN), (YAW_BINS, YAW_HIDDEN, 1, 1)).astype(np.float32), np.zeros(YAW_BINS, np.float32)))
    return params


def forward_yaw(params, x):
    """Logits (n, YAW_BINS)."""
    import jax
    from jax import lax
    dn = ("NCHW", "OIHW", "NCHW")
    h = x[:, None]
    for (w, b), (_, _, s, d) in zip(params[:-2], YAW_LAYERS):
        h = lax.conv_general_dilated(h, w, (s, s), [(d, d), (d, d)], rhs_dilation=(d, d), dimension_numbers=dn)
        h = jax.nn.relu(h + b[None, :, None, None])
    w, b = params[-2]
    h = jax.nn.relu(lax.conv_general_dilated(h, w, (1, 1), [(0, 0), (0, 0)], dimension_numbers=dn) + b[None, :, None, None])
    w, b = params[-1]
    h = lax.conv_general_dilated(h, w, (1, 1), [(0, 0), (0, 0)], dimension_numbers=dn) + b[None, :, None, None]
    return h[:, :, 0, 0]


def loss_yaw(params, x, t):
    import jax
    import jax.numpy as jnp
    z = forward_yaw(params, x)
    return -jnp.mean(jnp.sum(t * jax.nn.log_softmax(z, axis=1), axis=1))


def yaw_of(z):
    """Mean and standard deviation (degrees) of the bin distribution of logits `z` (as
    `HubYawNet` in heat.rs)."""
    p = np.exp(z - z.max(1, keepdims=True))
    p /= p.sum(1, keepdims=True)
    mean = p @ YAW_CENTRES
    std = np.sqrt(np.maximum((p * (YAW_CENTRES[None, :] - mean[:, None]) ** 2).sum(1), 0))
    return mean, std


def evaluate_yaw(params, frames, labels, fwd):
    """Held-out frames (hub and distance exact): error per distance band, the sign where the
    yaw is beyond 4 degrees, and how the spread tracks the error."""
    rng = np.random.default_rng(12345)
    idx = np.arange(len(frames))
    x, yaws = sample_yaw_crops(frames, labels, idx, rng, jitter=False)
    z = np.concatenate([np.asarray(fwd(params, x[i:i + 256] / 255.0)) for i in range(0, len(x), 256)])
    mean, std = yaw_of(z)
    err = mean - yaws
    dist = labels[idx, 2]
    out = {}
    for lo, hi in [(3.5, 8), (8, 15), (15, 25), (25, 32), (32, 46)]:
        m = (dist >= lo) & (dist < hi)
        if m.any():
            big = m & (np.abs(yaws) > 4)
            out[f"{lo:g}-{hi:g}m"] = {
                "n": int(m.sum()),
                "mae": round(float(np.abs(err[m]).mean()), 2),
                "within3_%": round(100 * float((np.abs(err[m]) <= 3).mean()), 1),
                "sign_ok_%": round(100 * float((np.sign(mean[big]) == np.sign(yaws[big])).mean()), 1) if big.any() else None,
                "std_med": round(float(np.median(std[m])), 2),
            }
    return out


def export_yaw(params, path):
    """The yaw network as ONNX: the 3x3 stack, then the 8x8 "fully connected" layer and the bins."""
    from onnx import helper, numpy_helper
    nodes, inits, prev = conv_stack(params[:-2], YAW_LAYERS)
    (wh, bh), (wo, bo) = params[-2], params[-1]
    inits += [numpy_helper.from_array(np.asarray(wh, np.float32), "wh"), numpy_helper.from_array(np.asarray(bh, np.float32), "bh"),
              numpy_helper.from_array(np.asarray(wo, np.float32), "wout"), numpy_helper.from_array(np.asarray(bo, np.float32), "bout")]
    nodes.append(helper.make_node("Conv", [prev, "wh", "bh"], ["ch"], kernel_shape=[8, 8]))
    nodes.append(helper.make_node("Relu", ["ch"], ["rh"]))
    nodes.append(helper.make_node("Conv", ["rh", "wout", "bout"], ["logits"], kernel_shape=[1, 1]))
    save_onnx(nodes, inits, path, "hubyaw", [1, 1, YAW_SIDE, YAW_SIDE], [1, YAW_BINS, 1, 1])


def load_onnx(path, n_layers):
    """The parameters of a heatmap or crop model written by `export`."""
    import onnx
    from onnx import numpy_helper
    w = {t.name: numpy_helper.to_array(t) for t in onnx.load(path).graph.initializer}
    return [(w[f"w{i}"], w[f"b{i}"]) for i in range(n_layers)] + [(w["wout"], w["bout"])]


def load_yaw_onnx(path):
    """The parameters of a yaw model written by `export_yaw`."""
    import onnx
    from onnx import numpy_helper
    w = {t.name: numpy_helper.to_array(t) for t in onnx.load(path).graph.initializer}
    params = [(w[f"w{i}"], w[f"b{i}"]) for i in range(len(YAW_LAYERS))]
    return params + [(w["wh"], w["bh"]), (w["wout"], w["bout"])]


def train_yaw(a):
    """`--model yaw`: the relative-yaw network (or, with `--evaluate`, scores a trained one)."""
    import jax
    import jax.numpy as jnp
    import optax

    tag = "[train-hubnet yaw]"
    if a.evaluate:
        frames, labels = load_yaw(a.data)
        print(f"{tag} {a.evaluate} on {len(frames)} frames: {evaluate_yaw(load_yaw_onnx(a.evaluate), frames, labels, jax.jit(forward_yaw))}")
        return 0
    train_dirs, hold_dirs = (a.data[:-1], a.data[-1:]) if len(a.data) > 1 else (a.data, [])
    x, labels = load_yaw(train_dirs)
    print(f"{tag} {len(x)} training frames from {', '.join(train_dirs)}", flush=True)
    hold = load_yaw(hold_dirs) if hold_dirs else None
    rng = np.random.default_rng(a.seed)
    params = [tuple(jnp.asarray(p) for p in layer) for layer in init_yaw(rng)]
    steps = a.epochs * (a.crops_per_epoch // a.batch)
    opt = optax.adamw(optax.cosine_decay_schedule(a.lr, steps), weight_decay=1e-4)
    state = opt.init(params)
    fwd = jax.jit(forward_yaw)

    @jax.jit
    def step(params, state, xb, tb):
        loss, g = jax.value_and_grad(lambda p: loss_yaw(p, xb, tb))(params)
        upd, state = opt.update(g, state, params)
        return optax.apply_updates(params, upd), state, loss

    t0 = time.time()
    for epoch in range(a.epochs):
        losses = []
        for _ in range(a.crops_per_epoch // a.batch):
            xb, yb = sample_yaw_crops(x, labels, rng.integers(0, len(x), a.batch), rng)
            xb, _ = photometric(xb.astype(np.float32) / 255.0, -np.ones((len(xb), 2), np.float32), rng, mirror=False)
            params, state, loss = step(params, state, xb, yaw_targets(yb))
            losses.append(float(loss))
        msg = f"{tag} epoch {epoch + 1}/{a.epochs} loss {np.mean(losses):.4f} ({time.time() - t0:.0f} s)"
        if hold is not None and (epoch + 1 == a.epochs or epoch % 3 == 2):
            msg += f" held out: {evaluate_yaw(params, hold[0], hold[1], fwd)}"
        print(msg, flush=True)
    export_yaw([tuple(np.asarray(p) for p in layer) for layer in params], a.out)
    print(f"{tag} wrote {a.out}")


def conv_stack(params, layers):
    """ONNX nodes and initialisers of the 3x3 Conv+Relu layers from "input" (names w{i}, b{i}),
    and the name of the last output."""
    from onnx import helper, numpy_helper
    nodes, inits = [], []
    prev = "input"
    for i, ((w, b), (_, _, s, d)) in enumerate(zip(params, layers)):
        inits += [numpy_helper.from_array(np.asarray(w, np.float32), f"w{i}"), numpy_helper.from_array(np.asarray(b, np.float32), f"b{i}")]
        nodes.append(helper.make_node("Conv", [prev, f"w{i}", f"b{i}"], [f"c{i}"], kernel_shape=[3, 3], strides=[s, s], pads=[d, d, d, d], dilations=[d, d]))
        nodes.append(helper.make_node("Relu", [f"c{i}"], [f"r{i}"]))
        prev = f"r{i}"
    return nodes, inits, prev


def save_onnx(nodes, inits, path, name, input_shape, output_shape):
    """Writes the graph (opset 11, IR 6: what OpenCV 4.6's dnn module reads) after checking it."""
    import onnx
    from onnx import TensorProto, helper
    graph = helper.make_graph(
        nodes,
        name,
        [helper.make_tensor_value_info("input", TensorProto.FLOAT, input_shape)],
        [helper.make_tensor_value_info("logits", TensorProto.FLOAT, output_shape)],
        inits,
    )
    model = helper.make_model(graph, producer_name="hubtrack train-hubnet", opset_imports=[helper.make_opsetid("", 11)])
    model.ir_version = 6
    onnx.checker.check_model(model)
    onnx.save(model, path)


def export(params, path, layers=LAYERS, size=(H, W), grid=(GH, GW), name="hubnet"):
    """The heatmap or crop network as ONNX: the 3x3 stack and a 1x1 convolution to the logit."""
    from onnx import helper, numpy_helper
    nodes, inits, prev = conv_stack(params[:-1], layers)
    w, b = params[-1]
    inits += [numpy_helper.from_array(np.asarray(w, np.float32), "wout"), numpy_helper.from_array(np.asarray(b, np.float32), "bout")]
    nodes.append(helper.make_node("Conv", [prev, "wout", "bout"], ["logits"], kernel_shape=[1, 1]))
    save_onnx(nodes, inits, path, name, [1, 1, size[0], size[1]], [1, 1, grid[0], grid[1]])


def main():
    global YAW_WINDOW_M, YAW_DISTANCE_RANGE_M
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("data", nargs="+", help="dataset folders (hubtrack dataset); the last is held out")
    ap.add_argument("--out", help="ONNX file to write (required unless --evaluate)")
    ap.add_argument("--model", choices=["frame", "crop", "yaw"], default="frame",
                    help="frame: the whole-frame heatmap (hubnet.onnx); crop: the hub crop network (hubcrop.onnx); "
                         "yaw: the relative-yaw network (hubyaw.onnx)")
    ap.add_argument("--epochs", type=int, default=20)
    ap.add_argument("--crops-per-epoch", type=int, default=20000, help="crop model: crops drawn per epoch")
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--lr", type=float, default=2e-3)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--evaluate", metavar="MODEL", help="score this ONNX file on all the folders, each on its own, instead of training")
    ap.add_argument("--yaw-window-m", type=float, default=YAW_WINDOW_M,
                    help="yaw model: the crop's width in metres at the hub's distance (keep in step with heat.rs: "
                         "YAW_WINDOW_M, YAW_CLOSE_WINDOW_M for the close-range model)")
    ap.add_argument("--yaw-range-m", type=float, nargs=2, default=YAW_DISTANCE_RANGE_M, metavar=("NEAR", "FAR"),
                    help="yaw model: train and score on frames whose hub is this far (metres)")
    ap.add_argument("--held-out", action="append", default=[], metavar="DIR",
                    help="frame and crop models: a further held-out folder, scored on its own beside the last one (repeatable)")
    a = ap.parse_args()
    if not a.out and not a.evaluate:
        ap.error("--out is required")
    import jax
    import jax.numpy as jnp
    import optax

    if a.model == "yaw":
        YAW_WINDOW_M, YAW_DISTANCE_RANGE_M = a.yaw_window_m, tuple(a.yaw_range_m)
        return train_yaw(a)
    crop_model = a.model == "crop"
    layers = CROP_LAYERS if crop_model else LAYERS
    tag = "[train-hubnet" + (" crop]" if crop_model else "]")
    fwd = jax.jit(lambda p, xb: forward(p, xb, layers))
    score = (lambda p, h: evaluate_crops(p, h[0], h[1], fwd)) if crop_model else (lambda p, h: evaluate(p, h[0], h[1], fwd))
    if a.evaluate:
        params = load_onnx(a.evaluate, len(layers))
        for d in a.data + a.held_out:
            print(f"{tag} {a.evaluate} on {d}: {score(params, load([d], any_size=crop_model))}", flush=True)
        return 0
    train_dirs, hold_dirs = (a.data[:-1], a.data[-1:]) if len(a.data) > 1 else (a.data, [])
    x, hubs = load(train_dirs, any_size=crop_model)
    print(f"{tag} {len(x)} training frames ({int((hubs[:, 0] >= 0).sum())} with a hub in view) from {', '.join(train_dirs)}", flush=True)
    holds = [(d, load([d], any_size=crop_model)) for d in hold_dirs + a.held_out]
    rng = np.random.default_rng(a.seed)
    params = [tuple(jnp.asarray(p) for p in layer) for layer in init(rng, layers)]
    per_epoch = a.crops_per_epoch if crop_model else len(x)
    steps = a.epochs * (per_epoch // a.batch)
    opt = optax.adamw(optax.cosine_decay_schedule(a.lr, steps), weight_decay=1e-4)
    state = opt.init(params)

    @jax.jit
    def step(params, state, xb, tb):
        loss, g = jax.value_and_grad(lambda p: loss_fn(p, xb, tb, layers))(params)
        upd, state = opt.update(g, state, params)
        return optax.apply_updates(params, upd), state, loss

    t0 = time.time()
    for epoch in range(a.epochs):
        losses = []
        if crop_model:
            for _ in range(per_epoch // a.batch):
                xb, hb, _ = sample_crops(x, hubs, rng.integers(0, len(x), a.batch), rng)
                xb, hb = augment(xb, hb, rng, zoom=False)
                params, state, loss = step(params, state, xb, targets(hb, CROP_GRID, CROP_GRID))
                losses.append(float(loss))
        else:
            order = rng.permutation(len(x))
            for i in range(0, len(order) - a.batch + 1, a.batch):
                idx = order[i:i + a.batch]
                xb, hb = augment(x[idx], hubs[idx], rng)
                params, state, loss = step(params, state, xb, targets(hb))
                losses.append(float(loss))
        msg = f"{tag} epoch {epoch + 1}/{a.epochs} loss {np.mean(losses):.4f} ({time.time() - t0:.0f} s)"
        if epoch + 1 == a.epochs or epoch % 3 == 2:
            for d, hold in holds:
                msg += f"\n  held out {d}: {score(params, hold)}"
        print(msg, flush=True)
    params = [tuple(np.asarray(p) for p in layer) for layer in params]
    if crop_model:
        export(params, a.out, CROP_LAYERS, (CROP_SIDE, CROP_SIDE), (CROP_GRID, CROP_GRID), "hubcrop")
    else:
        export(params, a.out)
    print(f"{tag} wrote {a.out}")


if __name__ == "__main__":
    sys.exit(main())
