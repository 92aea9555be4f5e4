#!/usr/bin/env python3
"""Train the learned hub heatmap (`libs/detect/src/heat.rs`) on frames `hubtrack dataset` rendered.

The network maps the detector's 192x128 grey network input to one logit per 8x8-pixel cell:
"the rotor's hub lies in this cell". It is trained on the project's own renderer only (never on
`../shared/data`), with augmentations that take away what the renderer gets too easy (the
turbine's shade, the sky's brightness, sharpness, framing): brightness inversion, gamma,
contrast, noise, blur, zoom and mirror. The result is written as ONNX (opset 11, plain
Conv/Relu, which OpenCV 4.6's dnn module reads) for `include_bytes!` in the detector.

Usage: train-hubnet.py --out libs/detect/models/hubnet.onnx [--epochs N] DATASET_DIR...
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


def load(dirs):
    from PIL import Image
    xs, ys = [], []
    for d in dirs:
        for line in open(os.path.join(d, "labels.jsonl")):
            r = json.loads(line)
            img = np.asarray(Image.open(os.path.join(d, r["file"])).convert("L"), dtype=np.uint8)
            assert img.shape == (H, W), (r["file"], img.shape)
            xs.append(img)
            hub = r["hub"]
            ys.append(hub if hub is not None and 0 <= hub[0] <= 1 and 0 <= hub[1] <= 1 else [-1.0, -1.0])
    return np.stack(xs), np.asarray(ys, dtype=np.float32)


def targets(hubs):
    """Gaussian bumps (peak 1) on the cell grid around each hub; all zero without one."""
    gx = (np.arange(GW) + 0.5) / GW
    gy = (np.arange(GH) + 0.5) / GH
    dx = (gx[None, None, :] - hubs[:, 0, None, None]) * GW
    dy = (gy[None, :, None] - hubs[:, 1, None, None]) * GH
    t = np.exp(-(dx**2 + dy**2) / (2 * SIGMA_CELLS**2))
    t[hubs[:, 0] < 0] = 0.0
    return t.astype(np.float32)


def augment(x, hubs, rng):
    """Random photometric and geometric changes; returns float images in [0, 1] and hubs."""
    n = len(x)
    x = x.astype(np.float32) / 255.0
    hubs = hubs.copy()
    # Zoom in (crop and scale back) on part of the batch, nearest-neighbour.
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
    x = out
    flip = rng.random(n) < 0.5
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


def init(rng):
    params = []
    for cin, cout, _, _ in LAYERS:
        w = rng.normal(0, np.sqrt(2.0 / (cin * 9)), (cout, cin, 3, 3)).astype(np.float32)
        params.append((w, np.zeros(cout, np.float32)))
    cin = LAYERS[-1][1]
    params.append((rng.normal(0, np.sqrt(1.0 / cin), (1, cin, 1, 1)).astype(np.float32), np.full(1, -4.0, np.float32)))
    return params


def forward(params, x):
    import jax
    from jax import lax
    h = x[:, None]
    for (w, b), (_, _, s, d) in zip(params[:-1], LAYERS):
        h = lax.conv_general_dilated(h, w, (s, s), [(d, d), (d, d)], rhs_dilation=(d, d), dimension_numbers=("NCHW", "OIHW", "NCHW"))
        h = jax.nn.relu(h + b[None, :, None, None])
    w, b = params[-1]
    h = lax.conv_general_dilated(h, w, (1, 1), [(0, 0), (0, 0)], dimension_numbers=("NCHW", "OIHW", "NCHW"))
    return h[:, 0] + b[0]


def loss_fn(params, x, t):
    import jax.numpy as jnp
    z = forward(params, x)
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


def export(params, path):
    import onnx
    from onnx import TensorProto, helper, numpy_helper
    nodes, inits = [], []
    prev = "input"
    for i, ((w, b), (_, _, s, d)) in enumerate(zip(params[:-1], LAYERS)):
        inits += [numpy_helper.from_array(np.asarray(w, np.float32), f"w{i}"), numpy_helper.from_array(np.asarray(b, np.float32), f"b{i}")]
        nodes.append(helper.make_node("Conv", [prev, f"w{i}", f"b{i}"], [f"c{i}"], kernel_shape=[3, 3], strides=[s, s], pads=[d, d, d, d], dilations=[d, d]))
        nodes.append(helper.make_node("Relu", [f"c{i}"], [f"r{i}"]))
        prev = f"r{i}"
    w, b = params[-1]
    inits += [numpy_helper.from_array(np.asarray(w, np.float32), "wout"), numpy_helper.from_array(np.asarray(b, np.float32), "bout")]
    nodes.append(helper.make_node("Conv", [prev, "wout", "bout"], ["logits"], kernel_shape=[1, 1]))
    graph = helper.make_graph(
        nodes,
        "hubnet",
        [helper.make_tensor_value_info("input", TensorProto.FLOAT, [1, 1, H, W])],
        [helper.make_tensor_value_info("logits", TensorProto.FLOAT, [1, 1, GH, GW])],
        inits,
    )
    model = helper.make_model(graph, producer_name="hubtrack train-hubnet", opset_imports=[helper.make_opsetid("", 11)])
    model.ir_version = 6
    onnx.checker.check_model(model)
    onnx.save(model, path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("data", nargs="+", help="dataset folders (hubtrack dataset); the last is held out")
    ap.add_argument("--out", required=True, help="ONNX file to write")
    ap.add_argument("--epochs", type=int, default=20)
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--lr", type=float, default=2e-3)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    import jax
    import jax.numpy as jnp
    import optax

    train_dirs, hold_dirs = (a.data[:-1], a.data[-1:]) if len(a.data) > 1 else (a.data, [])
    x, hubs = load(train_dirs)
    print(f"[train-hubnet] {len(x)} training frames ({int((hubs[:, 0] >= 0).sum())} with a hub in view) from {', '.join(train_dirs)}", flush=True)
    hold = load(hold_dirs) if hold_dirs else None
    rng = np.random.default_rng(a.seed)
    params = [tuple(jnp.asarray(p) for p in layer) for layer in init(rng)]
    steps = a.epochs * (len(x) // a.batch)
    opt = optax.adamw(optax.cosine_decay_schedule(a.lr, steps), weight_decay=1e-4)
    state = opt.init(params)
    fwd = jax.jit(forward)

    @jax.jit
    def step(params, state, xb, tb):
        loss, g = jax.value_and_grad(loss_fn)(params, xb, tb)
        upd, state = opt.update(g, state, params)
        return optax.apply_updates(params, upd), state, loss

    t0 = time.time()
    for epoch in range(a.epochs):
        order = rng.permutation(len(x))
        losses = []
        for i in range(0, len(order) - a.batch + 1, a.batch):
            idx = order[i:i + a.batch]
            xb, hb = augment(x[idx], hubs[idx], rng)
            params, state, loss = step(params, state, xb, targets(hb))
            losses.append(float(loss))
        msg = f"[train-hubnet] epoch {epoch + 1}/{a.epochs} loss {np.mean(losses):.4f} ({time.time() - t0:.0f} s)"
        if hold is not None and (epoch + 1 == a.epochs or epoch % 3 == 2):
            msg += f" held out: {evaluate(params, hold[0], hold[1], fwd)}"
        print(msg, flush=True)
    export([tuple(np.asarray(p) for p in layer) for layer in params], a.out)
    print(f"[train-hubnet] wrote {a.out}")


if __name__ == "__main__":
    sys.exit(main())
