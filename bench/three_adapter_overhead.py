#!/usr/bin/env python3
"""The three.js adapter's overhead per frame against three.js's own frame time (bench/RESULTS.md).

Runs one sweep through the adapter (sphere_on_plane at 640x360, PCF, 10 normal biases x 5 map
sizes: 50 frames in one batch) and sets, per frame, the file exchange beside the renderer's
frame_ms: on the adapter's side the pixels decoded from the page and the PNGs encoded and written
(adapter.log's "exchange"), on shadowlab's side the frame's files read and checked
(adapter_decode_ms). Prints the medians and their ratio.

usage: bench/three_adapter_overhead.py [SHADOWLAB] [OUT]   (default build/app/shadowlab, out/three_overhead)
"""
import json
import os
import re
import shutil
import statistics
import subprocess
import sys

here = os.path.dirname(os.path.abspath(__file__))
shadowlab = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "build", "app", "shadowlab")
out = sys.argv[2] if len(sys.argv) > 2 else os.path.join(here, "..", "out", "three_overhead")
shutil.rmtree(out, ignore_errors=True)
subprocess.run([shadowlab, "sweep", "sphere_on_plane", "--set", "renderer=three",
                "--set", "scene:/camera/width=640", "--set", "scene:/camera/height=360",
                "--grid", "three.normal_bias=0,0.01,0.02,0.03,0.05,0.07,0.1,0.15,0.2,0.3", "--grid", "three.map_size=256,512,1024,2048,4096",
                "--no-report", "-o", out], check=True, stdout=subprocess.DEVNULL)
rows = json.load(open(os.path.join(out, "results.json")))["rows"]
log = open(os.path.join(out, "adapter", "sphere_on_plane", "batch-0", "adapter.log")).read()
exchange = [float(x) for x in re.findall(r"\(exchange ([0-9.]+) ms\)", log)]
frame = [r["timings"]["renderer_frame_ms"] for r in rows]
decode = [r["timings"]["adapter_decode_ms"] for r in rows]
if len(exchange) != len(rows):
    sys.exit(f"expected {len(rows)} exchange lines in adapter.log, found {len(exchange)}")
per = [e + d for e, d in zip(exchange, decode)]
m = statistics.median
print(f"frames {len(rows)}: renderer frame_ms median {m(frame):.2f}; exchange (adapter) median {m(exchange):.2f} ms, "
      f"decode (shadowlab) median {m(decode):.2f} ms; overhead median {m(per):.2f} ms = "
      f"{100 * m(per) / m(frame):.1f} % of the frame (per frame, worst {100 * max(p / f for p, f in zip(per, frame)):.1f} %)")
