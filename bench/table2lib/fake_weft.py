"""A stand-in for the weft binary in test_cli.py: the commands bench/table2.py runs (scene,
render, render merge, compare, montage, gather, fit, --version), answering in weft's formats
with made-up, deterministic numbers, in milliseconds. Renders are JSON files named .exr; the
figures are real PNGs. Only for tests: no number it prints means anything.

    python3 fake_weft.py render SCENE --mode fiber --spp 64 --seed 1 --out OUT.exr
"""
import json
import os
import struct
import sys
import zlib

# relMSE of a mode's render at n spp against the true image: C[mode] / n.
C = {"fiber": 4.0, "neural": 1.0, "dual": 8.0}
SECONDS_PER_SPP = {"fiber": 0.5, "neural": 0.02, "dual": 0.015}
RAYS_PER_SAMPLE = {"fiber": 60.0, "neural": 4.0, "dual": 3.5}
GEOMETRY = {"fiber": 200000000, "neural": 450000, "dual": 450000}
MATERIAL = {"fiber": 100000, "neural": 1000000, "dual": 200000}
# The mode's mean relative to the fiber image (a bias), and its error beyond noise.
BIAS = {"fiber": 1.0, "neural": 1.01, "dual": 0.6}
ERROR = {"fiber": 0.0, "neural": 0.002, "dual": 0.25}


def flag(args, name, default=None):
    return args[args.index(name) + 1] if name in args else default


def write_json(path, data):
    with open(path, "w") as f:
        json.dump(data, f, indent=1)


def write_png(path, width, height, rgb):
    """A width x height PNG of one colour."""
    raw = b"".join(b"\0" + bytes(rgb) * width for _ in range(height))

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff))
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8,
                                                                   2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def scene(args):
    out = flag(args, "--out")
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "yarns.txt"), "w") as f:
        f.write("0 0 0\n1 0 0\n")
    size = int(flag(args, "--width", 16))
    write_json(os.path.join(out, "scene.json"), {
        "film": {"width": size, "height": int(flag(args, "--height", size))},
        "yarns": [{"curves": "yarns.txt", "model": flag(args, "--model")}]})
    print(json.dumps({"out": out}))


def render_stats(mode, spp, seed, width, height, threads, shards=1):
    seconds = spp * SECONDS_PER_SPP[mode] * (1 + 0.01 * (seed % 3))
    rays = RAYS_PER_SAMPLE[mode] * width * height * spp
    return {"mode": mode, "spp": spp, "seed": seed, "width": width, "height": height,
            "threads": threads, "seconds": seconds, "seconds_per_spp": seconds / spp,
            "rays": rays, "max_depth": 1000, "truncated_fraction": 0.0,
            "yarn_sampling": "tabulated" if mode == "neural" else None,
            "peak_resident_bytes": GEOMETRY[mode] + MATERIAL[mode] + 10000000,
            "shards": {"count": shards},
            "scene": {"build_seconds": 0.1, "geometry_bvh_bytes": GEOMETRY[mode],
                      "material_bytes": MATERIAL[mode], "tubes": 3}}


def render(args):
    if args[1] == "merge":
        out = flag(args, "--out")
        parts = [a for a in args[2:args.index("--out")]]
        stats = []
        for p in parts:
            with open(os.path.splitext(p)[0] + ".json") as f:
                stats.append(json.load(f))
        merged = render_stats(stats[0]["mode"], sum(s["spp"] for s in stats), stats[0]["seed"],
                              stats[0]["width"], stats[0]["height"], stats[0]["threads"],
                              len(parts))
        merged["seconds"] = sum(s["seconds"] for s in stats)
        merged["seconds_per_spp"] = merged["seconds"] / merged["spp"]
    else:
        with open(args[1]) as f:
            film = json.load(f)["film"]
        mode, seed = flag(args, "--mode"), int(flag(args, "--seed"))
        threads = int(flag(args, "--threads", 0)) or 2
        if "--spp" in args:
            spp = int(flag(args, "--spp"))
        else:
            spp = max(1, int(float(flag(args, "--time")) / SECONDS_PER_SPP[mode]))
        shards = int(flag(args, "--shard", "0/1").split("/")[1])
        merged = render_stats(mode, spp, seed, film["width"], film["height"], threads)
        if shards > 1:  # a part: its share of the samples
            merged = render_stats(mode, max(1, spp // shards), seed, film["width"],
                                  film["height"], threads)
        out = flag(args, "--out")
    os.makedirs(os.path.dirname(out), exist_ok=True)
    write_json(out, {"fake_image": merged["mode"], "spp": merged["spp"]})
    write_json(os.path.splitext(out)[0] + ".json", merged)


def compare(args):
    images = []
    for path in args[1:3]:
        with open(path) as f:
            images.append(json.load(f))
    a, b = images
    noise = C[a["fake_image"]] / a["spp"] + C[b["fake_image"]] / b["spp"]
    error = abs(ERROR[a["fake_image"]] - ERROR[b["fake_image"]])
    scale = int(flag(args, "--scale", 1))
    rel_mse = error + noise
    ratio = BIAS[a["fake_image"]] / BIAS[b["fake_image"]]
    if "--heatmap" in args:
        write_png(flag(args, "--heatmap"), 16, 16, (200, 10, 10))
    print(json.dumps({"ssim": 1 - rel_mse / scale, "rel_mse": rel_mse,
                      "mean_ratio": [ratio, ratio, None]}))


def montage(args):
    out = flag(args, "--out")
    images = [a for a in args[1:] if not a.startswith("--") and a != out]
    colour = zlib.crc32(" ".join(os.path.basename(i) for i in images).encode())
    write_png(out, 4 + 20 * len(images), 24, (colour & 255, (colour >> 8) & 255, 128))


def main(args):
    if args == ["--version"]:
        print("weft 0.0 (fake_weft.py)")
    elif args[0] == "scene":
        scene(args)
    elif args[0] == "render":
        render(args)
    elif args[0] == "compare":
        compare(args)
    elif args[0] == "montage":
        montage(args)
    elif args[0] == "gather":
        os.makedirs(flag(args, "--out"), exist_ok=True)
    elif args[0] == "fit" and "--print-config" in args:
        print(json.dumps({"t_net": {"steps": 10}, "m_net": {"steps": 10}}))
    elif args[0] == "fit":
        write_json(flag(args, "--out"), {"fake_model": True})
    else:
        sys.exit("fake_weft: unknown command %s" % " ".join(args))


if __name__ == "__main__":
    main(sys.argv[1:])
