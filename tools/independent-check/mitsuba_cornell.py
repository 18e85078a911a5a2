#!/usr/bin/env python3
"""Renders an OBJ + MTL scene with Mitsuba 3 (an established, independent path
tracer) under the project's physics, for the once-recorded check of
`solver reference` in docs/accuracy.md.

Physics matched to the solver and `solver reference` (design notes, "Truth, not
self-consistency"): one-sided Lambertian emitters of radiance Ke (Mitsuba's
`area` emitter emits on the front side only), one-sided Lambertian surfaces of
albedo Kd (Mitsuba's `diffuse` BSDF is black from behind), pixels that are the
mean radiance over their square footprint (`box` reconstruction filter), and
unbiased unlimited-depth paths (`path` with max_depth -1 and Russian roulette).
Polygons are fan-triangulated, as the OBJ's header suggests for its slightly
non-planar quads. Mitsuba's `*_rgb` variants render linear RGB, the same
colour model as the solver.

Camera: Mitsuba's `look_at` sensor has the project's image orientation (the
eye's right is forward × up, row 0 at the top; checked once on the Cornell box,
whose red wall at +x is on the left from the standard camera), so its pixels are
those of `runtime screenshot --mono` and `solver reference`.

Usage (pip install mitsuba numpy):
    python3 tools/independent-check/mitsuba_cornell.py SCENE.obj OUT.npy \
        --eye 278 273 -800 --target 278 273 0 --up 0 1 0 --fov-y 39.3077 \
        --size 256x256 --spp 4096 --seed 1
OUT.npy is float32 H x W x 3 linear radiance, row 0 at the top, which
`solver compare` reads. It prints the render time.
"""
import argparse
import os
import sys
import time

import mitsuba as mi
import numpy as np


def parse_mtl(path):
    materials, name = {}, None
    for raw in open(path, encoding="utf-8"):
        words = raw.split("#", 1)[0].split()
        if not words:
            continue
        if words[0] == "newmtl":
            name = words[1]
            materials[name] = {"Kd": [0.0] * 3, "Ke": [0.0] * 3}
        elif name and words[0] in ("Kd", "Ke"):
            materials[name][words[0]] = [float(v) for v in words[1:4]]
    return materials


def parse_obj(path):
    """Returns (materials, [(material, [triangle as 3 positions])])."""
    positions, groups, current, mtl = [], {}, None, {}
    base = os.path.dirname(path)
    for raw in open(path, encoding="utf-8"):
        words = raw.split("#", 1)[0].split()
        if not words:
            continue
        if words[0] == "v":
            positions.append([float(v) for v in words[1:4]])
        elif words[0] == "mtllib":
            mtl.update(parse_mtl(os.path.join(base, words[1])))
        elif words[0] == "usemtl":
            current = words[1]
        elif words[0] == "f":
            idx = []
            for w in words[1:]:
                i = int(w.split("/")[0])
                idx.append(i - 1 if i > 0 else len(positions) + i)
            for k in range(1, len(idx) - 1):
                groups.setdefault(current, []).append(
                    [positions[idx[0]], positions[idx[k]], positions[idx[k + 1]]])
    return mtl, groups


def write_obj(path, triangles):
    """One material's triangles as a small OBJ that Mitsuba's `obj` shape loads."""
    with open(path, "w", encoding="utf-8") as out:
        for tri in triangles:
            for p in tri:
                out.write(f"v {p[0]!r} {p[1]!r} {p[2]!r}\n")
        for t in range(len(triangles)):
            out.write(f"f {3 * t + 1} {3 * t + 2} {3 * t + 3}\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("out")
    ap.add_argument("--eye", nargs=3, type=float, default=[278, 273, -800])
    ap.add_argument("--target", nargs=3, type=float, default=[278, 273, 0])
    ap.add_argument("--up", nargs=3, type=float, default=[0, 1, 0])
    ap.add_argument("--fov-y", type=float, default=39.3077)
    ap.add_argument("--size", default="256x256")
    ap.add_argument("--spp", type=int, default=1024)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--variant", default="scalar_rgb",
                    help="scalar_rgb, or llvm_ad_rgb (several times faster; needs a libLLVM, "
                         "e.g. Debian's libllvm16, found through DRJIT_LIBLLVM_PATH)")
    args = ap.parse_args()
    width, height = (int(v) for v in args.size.lower().split("x"))

    mi.set_variant(args.variant)
    materials, groups = parse_obj(args.scene)
    workdir = os.path.dirname(os.path.abspath(args.out))
    scene = {"type": "scene", "integrator": {"type": "path", "max_depth": -1}}
    for i, (name, triangles) in enumerate(groups.items()):
        m = materials[name]
        mesh_path = os.path.join(workdir, f".mitsuba_{i}.obj")
        write_obj(mesh_path, triangles)
        shape = {"type": "obj", "filename": mesh_path, "face_normals": True,
                 "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": m["Kd"]}}}
        if max(m["Ke"]) > 0:
            shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": m["Ke"]}}
        scene[f"shape_{i}"] = shape
    look = mi.ScalarTransform4f.look_at(origin=args.eye, target=args.target, up=args.up)
    scene["sensor"] = {
        "type": "perspective",
        "fov_axis": "y",
        "fov": args.fov_y,
        "to_world": look,
        "sampler": {"type": "independent", "sample_count": args.spp, "seed": args.seed},
        "film": {"type": "hdrfilm", "width": width, "height": height,
                 "rfilter": {"type": "box"}, "pixel_format": "rgb"},
    }
    loaded = mi.load_dict(scene)
    start = time.time()
    image = np.array(mi.render(loaded, spp=args.spp, seed=args.seed), dtype=np.float32)
    seconds = time.time() - start
    for i in range(len(groups)):
        os.remove(os.path.join(workdir, f".mitsuba_{i}.obj"))
    tmp = args.out + ".tmp.npy"
    np.save(tmp, image[:, :, :3])
    os.replace(tmp, args.out)
    print(f"mitsuba {mi.__version__} {args.variant}: {width}x{height} at {args.spp} spp "
          f"in {seconds:.1f} s -> {args.out} (mean {image[:, :, :3].mean():.5f})")


if __name__ == "__main__":
    sys.exit(main())
