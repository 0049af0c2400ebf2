#!/usr/bin/env python3
"""shadowlab's own rasterizer as an adapter (adapters/README.md): for each frame of the request,
`shadowlab raster` on the source scene with the frame's keys, its raster.exr left in the frame's
folder and renderer.json written last. The smallest complete adapter: what an adapter reads, what
it writes, and how a frame that fails is reported (error.txt) while the others go on.

usage: adapter.py REQUEST.json SHADOWLAB
"""
import json
import os
import subprocess
import sys


def fail(message, code=2):
    print(f"shadowlab-raster adapter: error: {message}", file=sys.stderr)
    sys.exit(code)


def value_text(value):
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value) if not isinstance(value, float) else repr(value)


def main():
    if len(sys.argv) != 3:
        fail("usage: adapter.py REQUEST.json SHADOWLAB")
    request_path, shadowlab = sys.argv[1], sys.argv[2]
    try:
        with open(request_path, encoding="utf-8") as f:
            request = json.load(f)
    except (OSError, ValueError) as e:
        fail(f"{request_path}: cannot read the request: {e}")
    if not isinstance(request, dict) or request.get("shadowlab_adapter_request") != 1:
        fail(f"{request_path}: expected a request of protocol 1")
    source = request.get("source_scene") or {}
    scene = source.get("path")
    frames = request.get("frames")
    if not isinstance(scene, str) or not isinstance(frames, list):
        fail(f"{request_path}: expected source_scene.path and frames")
    scene_sets = []
    for o in source.get("overrides", []):
        scene_sets += ["--set", "scene:" + o["pointer"] + "=" + json.dumps(o["value"])]
    for frame in frames:
        out = frame["out"]
        args = [shadowlab, "raster", scene, "--light", request["light"], "-o", out] + scene_sets
        for key, value in sorted(frame["keys"].items()):
            args += ["--set", f"{key}={value_text(value)}"]
        print("$ " + " ".join(args), flush=True)
        done = subprocess.run(args, stdout=sys.stdout, stderr=sys.stderr)
        if done.returncode != 0:
            with open(os.path.join(out, "error.txt"), "w", encoding="utf-8") as f:
                f.write(f"shadowlab raster exited with status {done.returncode}\n")
            continue
        with open(os.path.join(out, "raster.json"), encoding="utf-8") as f:
            timings = json.load(f)
        renderer = {
            "name": "shadowlab raster (" + timings.get("device", "") + ")",
            "frame_ms": timings["method_gpu_ms"],
            "settings": frame["keys"],
        }
        tmp = os.path.join(out, "renderer.json.tmp")
        with open(tmp, "w", encoding="utf-8") as f:
            json.dump(renderer, f, indent=2)
        os.replace(tmp, os.path.join(out, "renderer.json"))


if __name__ == "__main__":
    main()
