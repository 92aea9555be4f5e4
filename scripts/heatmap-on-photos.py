#!/usr/bin/env python3
"""Writes photos with truth (the format of ../shared/data/*/truth.jsonl) as a folder that
`train-hubnet.py --evaluate MODEL DIR` scores a hub heatmap on: the network's input approximated
(grey, halved by 2x2 means down to at most 500 px wide, area-resized to 192x128, as the
detector's pyramid and `heat::network_input` do) and the hub as a fraction of the frame (the
blade axes' point). Evaluation only: never train on these.

Usage (in the training environment, scripts/train-hubnet.sh makes it):
       target/hubnet-venv/bin/python scripts/heatmap-on-photos.py ../shared/data/real-dev/truth.jsonl OUT_DIR
       target/hubnet-venv/bin/python scripts/train-hubnet.py --evaluate libs/detect/models/hubnet.onnx OUT_DIR
"""
import json, os, sys
from PIL import Image
truth, out = sys.argv[1], sys.argv[2]
base = os.path.dirname(truth)
os.makedirs(out, exist_ok=True)
with open(os.path.join(out, "labels.jsonl"), "w") as lab:
    for line in open(truth):
        t = json.loads(line)
        if t["set"] == "positive" and not t.get("hub_visible", True):
            continue
        im = Image.open(os.path.join(base, t["file"])).convert("L")
        w, h = im.size
        while im.size[0] > 500:
            im = im.reduce(2)
        im = im.resize((192, 128), Image.BOX)
        name = t["id"].replace("/", "_") + ".png"
        im.save(os.path.join(out, name))
        hub = t["axis_point"] if t["set"] == "positive" else None
        lab.write(json.dumps({"file": name, "hub": None if hub is None else [hub[0] / w, hub[1] / h]}) + "\n")
