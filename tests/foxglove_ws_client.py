"""An independent Foxglove WebSocket client (the `websockets` package speaking the published
protocol: subprotocol `foxglove.sdk.v1`, JSON `advertise` / `subscribe`, binary message data with
opcode 1), run as its own process by tests/test_live_view.py so that it can be killed abruptly.

Modes:
  receive: subscribe to TOPICS, receive for SECONDS, write the counts, bytes and arrival times per
           topic and the last video frame's JPEG to OUT, then keep the socket open until killed.
  stall:   subscribe to TOPICS and never read again (the socket's buffers fill up), until killed.
"""

import argparse
import base64
import json
import struct
import sys
import time

from websockets.sync.client import connect

SUBPROTOCOL = "foxglove.sdk.v1"
OP_MESSAGE_DATA = 0x01


def advertised(ws, topics, timeout):
    """Channels advertised by the server, by topic, once all of `topics` are there."""
    channels = {}
    deadline = time.monotonic() + timeout
    while not set(topics) <= set(channels):
        msg = ws.recv(timeout=max(0.1, deadline - time.monotonic()))
        if isinstance(msg, str):
            m = json.loads(msg)
            if m.get("op") == "advertise":
                for ch in m["channels"]:
                    channels[ch["topic"]] = ch
        if time.monotonic() > deadline:
            raise SystemExit(f"not advertised within {timeout}s: {set(topics) - set(channels)}")
    return channels


def annotation_time(a):
    """The timestamp (ns) of the first annotation of a `foxglove.ImageAnnotations`, if any."""
    for kind in ("circles", "points", "texts"):
        for item in a.get(kind, []):
            ts = item["timestamp"]
            return ts["sec"] * 1_000_000_000 + ts["nsec"]
    return None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("url")
    ap.add_argument("--topics", required=True)
    ap.add_argument("--mode", choices=["receive", "stall"], default="receive")
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--out")
    a = ap.parse_args()
    topics = a.topics.split(",")
    # max_queue=1: in stall mode the connection stops reading from the socket after one frame.
    with connect(a.url, subprotocols=[SUBPROTOCOL], max_size=None, open_timeout=10,
                 max_queue=1 if a.mode == "stall" else 256) as ws:
        return use_connection(ws, a, topics)


def use_connection(ws, a, topics):
    """Subscribes and receives (or stalls) on an open connection."""
    assert ws.subprotocol == SUBPROTOCOL, ws.subprotocol
    channels = advertised(ws, topics, 10.0)
    subs = {i + 1: t for i, t in enumerate(topics)}
    ws.send(json.dumps({"op": "subscribe", "subscriptions": [
        {"id": sid, "channelId": channels[t]["id"]} for sid, t in subs.items()]}))
    print(json.dumps({"subscribed": topics}), flush=True)
    if a.mode == "stall":
        while True:
            time.sleep(1)

    stats = {t: {"count": 0, "bytes": 0, "arrivals": [], "log_times": []} for t in topics}
    last_video = None
    start = time.monotonic()
    while time.monotonic() - start < a.seconds:
        try:
            msg = ws.recv(timeout=0.5)
        except TimeoutError:
            continue
        if isinstance(msg, str):
            continue
        if msg[0] != OP_MESSAGE_DATA:
            continue
        sid, log_time = struct.unpack_from("<IQ", msg, 1)
        payload = msg[13:]
        t = subs.get(sid)
        if t is None:
            continue
        s = stats[t]
        s["count"] += 1
        s["bytes"] += len(msg)
        s["arrivals"].append(time.monotonic() - start)
        s["log_times"].append(log_time)
        if t == "/frames":
            last_video = payload
        elif t == "/frames/overlay":
            s.setdefault("timestamps", []).append(annotation_time(json.loads(payload)))
    out = {"seconds": a.seconds, "topics": stats,
           "advertised": {t: ch["schemaName"] for t, ch in channels.items()},
           "schemas": {t: {k: channels[t][k] for k in ("encoding", "schemaName", "schemaEncoding")}
                       for t in topics},
           "frames_schema": base64.b64decode(channels["/frames"]["schema"]).hex()
           if "/frames" in channels else None,
           "last_video": last_video.hex() if last_video is not None else None}
    with open(a.out, "w") as f:
        json.dump(out, f)
    print(json.dumps({"done": True}), flush=True)
    # Keep the connection open: the test kills this process (no WebSocket close frame).
    while True:
        time.sleep(1)


if __name__ == "__main__":
    sys.exit(main())
