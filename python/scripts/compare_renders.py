#!/usr/bin/env python3
"""Rendered comparison: each material's own sampler vs the learned diffbsdf sampler inside
Mitsuba 3 (llvm_ad_rgb, `direct` integrator), BSDF sampling only and with MIS.

    target/pyvenv/bin/python python/scripts/compare_renders.py            # writes docs/rendering/

For each material: an object on a ground plane under a procedural sky (128x96), a
reference image (the material's own sampler with MIS at --ref-spp), MSE over the object's
pixels at several spp (mean of --seeds renders), wall time per render, efficiency
1 / (MSE * time per pixel sample), images side by side with error maps, a log-log plot of
MSE vs spp, a per-sample timing of `bsdf.sample` / `bsdf.pdf` inside Mitsuba, and
`results.json` / `results.md` (the tables in docs/rendering.md).
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import sys
import time
from typing import Any, Dict, List

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so")

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402

mi.set_variant("llvm_ad_rgb")

import diffbsdf  # noqa: E402
import diffbsdf.mitsuba_bsdf as dm  # noqa: E402
from diffbsdf import scenes  # noqa: E402

CONFIGS = [("own", "bsdf"), ("learned", "bsdf"), ("own", "mis"), ("learned", "mis")]


def materials(rgl: pathlib.Path) -> List[Dict[str, Any]]:
    m = ROOT / "models"
    return [
        {
            "key": "copper",
            "label": "rough copper (GGX alpha 0.3, Cu)",
            "model": m / "conductor-ggx-a0.3-cu-disk.dbsdf",
            "nested": {"type": "roughconductor", "distribution": "ggx", "alpha": 0.3, "material": "Cu"},
            "shape": "sphere",
        },
        {
            "key": "dielectric",
            "label": "rough dielectric (Beckmann alpha 0.3, eta 1.5), a pane",
            "model": m / "dielectric-beckmann-a0.3-sphere.dbsdf",
            "nested": {
                "type": "roughdielectric",
                "distribution": "beckmann",
                "alpha": 0.3,
                "int_ior": 1.5,
                "ext_ior": 1.0,
            },
            "shape": "rectangle",
        },
        {
            "key": "golden-yellow",
            "label": "RGL vch_golden_yellow (measured)",
            "model": m / "rgl-vch-golden-yellow-disk.dbsdf",
            "nested": {"type": "measured", "filename": str(rgl / "vch_golden_yellow_rgb.bsdf")},
            "shape": "sphere",
        },
        {
            "key": "irid-flake",
            "label": "RGL irid_flake_paint1 (measured)",
            "model": m / "rgl-irid-flake-paint1-disk.dbsdf",
            "nested": {"type": "measured", "filename": str(rgl / "irid_flake_paint1_rgb.bsdf")},
            "shape": "sphere",
        },
    ]


def bsdf_dict(mat: Dict[str, Any], sampler: str) -> Dict[str, Any]:
    if sampler == "own":
        return mat["nested"]
    return {"type": "diffbsdf", "model": str(mat["model"]), "bsdf": mat["nested"]}


def render(scene: Any, spp: int, seed: int) -> np.ndarray:
    img = mi.render(scene, seed=seed, spp=spp)
    return np.asarray(img, dtype=np.float64)


def tonemap(img: np.ndarray, exposure: float = 1.0) -> np.ndarray:
    x = np.clip(img * exposure, 0, None)
    x = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.clip(x, 0, 1)


def error_map(img: np.ndarray, ref: np.ndarray, scale: float) -> np.ndarray:
    """Absolute error (channel mean), black -> red -> yellow -> white at `scale`."""
    e = np.clip(np.abs(img - ref).mean(axis=2) / scale, 0, 1)
    return np.stack([np.clip(3 * e, 0, 1), np.clip(3 * e - 1, 0, 1), np.clip(3 * e - 2, 0, 1)], axis=2)


def write_png(path: pathlib.Path, rgb01: np.ndarray) -> None:
    arr = np.ascontiguousarray((rgb01 * 255 + 0.5).astype(np.uint8))
    mi.Bitmap(arr, mi.Bitmap.PixelFormat.RGB).write(str(path))


def time_sampling(mat: Dict[str, Any], n: int, reps: int) -> Dict[str, float]:
    """Seconds per call of `bsdf.sample` (value included) and `bsdf.pdf` on n random wi."""
    rng = np.random.default_rng(0)
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2]) + 0.05
    wi = (v / np.linalg.norm(v, axis=1, keepdims=True)).astype(np.float32)
    u = rng.random((n, 2), dtype=np.float32)
    out: Dict[str, float] = {}
    for sampler in ("own", "learned"):
        bsdf = mi.load_dict(bsdf_dict(mat, sampler))
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.wi = mi.Vector3f(np.ascontiguousarray(wi.T))
        ctx = mi.BSDFContext()
        s2 = mi.Point2f(np.ascontiguousarray(u.T))
        s1 = mi.Float(u[:, 0].copy())
        best_s, best_p = np.inf, np.inf
        for _ in range(reps + 1):  # the first run compiles the kernels
            t = time.perf_counter()
            bs, w = bsdf.sample(ctx, si, s1, s2)
            dr.eval(bs, w)
            dr.sync_thread()
            best_s = min(best_s, time.perf_counter() - t)
            t = time.perf_counter()
            p = bsdf.pdf(ctx, si, bs.wo)
            dr.eval(p)
            dr.sync_thread()
            best_p = min(best_p, time.perf_counter() - t)
        out[f"{sampler}_sample_us"] = best_s / n * 1e6
        out[f"{sampler}_pdf_us"] = best_p / n * 1e6
    return out


def svg_plot(results: Dict[str, Any], spps: List[int], path: pathlib.Path, by_time: bool = False) -> None:
    """Log-log MSE vs spp (or vs seconds per render: the equal-time view), one panel per
    material, one line per configuration."""
    keys = list(results)
    pw, ph, pad = 300, 220, 48
    colors = {"own/bsdf": "#1f77b4", "learned/bsdf": "#d62728", "own/mis": "#2ca02c", "learned/mis": "#ff7f0e"}
    dashes = {"own/bsdf": "", "learned/bsdf": "", "own/mis": "6,3", "learned/mis": "6,3"}
    W = len(keys) * (pw + pad) + pad
    H = ph + 2 * pad + 20
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="11">',
             f'<rect width="{W}" height="{H}" fill="white"/>']
    for i, k in enumerate(keys):
        if by_time:
            xs_all = [v for c in results[k]["seconds"].values() for v in c.values()]
            lx0, lx1 = np.floor(np.log10(min(xs_all))), np.ceil(np.log10(max(xs_all)))
            ticks = [10.0**e for e in range(int(lx0), int(lx1) + 1)]
        else:
            lx0, lx1 = np.log10(min(spps)), np.log10(max(spps))
            ticks = [float(s) for s in spps]
        x0 = pad + i * (pw + pad)
        y0 = pad
        mses = [v for c in results[k]["mse"].values() for v in c.values() if v > 0]
        ly0, ly1 = np.floor(np.log10(min(mses))), np.ceil(np.log10(max(mses)))

        def X(s: float) -> float:
            return x0 + (np.log10(s) - lx0) / (lx1 - lx0) * pw

        def Y(m: float) -> float:
            return y0 + ph - (np.log10(m) - ly0) / (ly1 - ly0) * ph

        parts.append(f'<rect x="{x0}" y="{y0}" width="{pw}" height="{ph}" fill="none" stroke="#888"/>')
        parts.append(f'<text x="{x0 + pw / 2}" y="{y0 - 8}" text-anchor="middle" font-weight="bold">{k}</text>')
        for s in ticks:
            label = f"{s:g} s" if by_time else f"{int(s)}"
            parts.append(f'<line x1="{X(s):.1f}" y1="{y0 + ph}" x2="{X(s):.1f}" y2="{y0 + ph + 4}" stroke="#444"/>')
            parts.append(f'<text x="{X(s):.1f}" y="{y0 + ph + 16}" text-anchor="middle">{label}</text>')
        for e in range(int(ly0), int(ly1) + 1):
            parts.append(f'<line x1="{x0}" y1="{Y(10.0**e):.1f}" x2="{x0 + pw}" y2="{Y(10.0**e):.1f}" stroke="#eee"/>')
            parts.append(f'<text x="{x0 - 4}" y="{Y(10.0**e) + 4:.1f}" text-anchor="end">1e{e}</text>')
        xlabel = "seconds per render (wall)" if by_time else "samples per pixel"
        parts.append(f'<text x="{x0 + pw / 2}" y="{y0 + ph + 32}" text-anchor="middle">{xlabel}</text>')
        for c, pts in results[k]["mse"].items():
            secs = results[k]["seconds"][c]
            xy = " ".join(
                f"{X(secs[s] if by_time else int(s)):.1f},{Y(m):.1f}" for s, m in pts.items() if m > 0
            )
            parts.append(f'<polyline points="{xy}" fill="none" stroke="{colors[c]}" stroke-width="2" stroke-dasharray="{dashes[c]}"/>')
    lx = pad
    for j, c in enumerate(colors):
        x = lx + j * 150
        parts.append(f'<line x1="{x}" y1="{H - 12}" x2="{x + 24}" y2="{H - 12}" stroke="{colors[c]}" stroke-width="2" stroke-dasharray="{dashes[c]}"/>')
        name = c.replace("own", "material's own").replace("/bsdf", ", BSDF only").replace("/mis", ", MIS")
        parts.append(f'<text x="{x + 30}" y="{H - 8}">{name}</text>')
    title = "equal time: MSE over the object vs render time" if by_time else "MSE over the object vs spp"
    parts.append(f'<text x="{W - pad}" y="{H - 8}" text-anchor="end">{title} (log-log)</text>')
    parts.append("</svg>")
    path.write_text("\n".join(parts) + "\n")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=str(ROOT / "docs" / "rendering"))
    ap.add_argument("--rgl", default=str(ROOT.parent / "shared" / "data" / "rgl"))
    ap.add_argument("--width", type=int, default=128)
    ap.add_argument("--height", type=int, default=96)
    ap.add_argument("--spp", default="1,4,16,64")
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--ref-spp", type=int, default=2048)
    ap.add_argument("--show-spp", type=int, default=16, help="spp of the images side by side")
    ap.add_argument("--only", default="", help="comma-separated material keys")
    ap.add_argument("--timing-n", type=int, default=1 << 18)
    args = ap.parse_args()

    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    spps = [int(s) for s in args.spp.split(",")]
    show_spp = min(spps, key=lambda s: abs(s - args.show_spp))
    dm.register()
    dm.wavefront()
    w, h = args.width, args.height
    t_start = time.perf_counter()
    results: Dict[str, Any] = {}
    mats = [m for m in materials(pathlib.Path(args.rgl)) if not args.only or m["key"] in args.only.split(",")]
    for mat in mats:
        key = mat["key"]
        print(f"== {key}: {mat['label']}", flush=True)
        ref_scene = mi.load_dict(scenes.object_scene(mat["nested"], "mis", w, h, 1, shape=mat["shape"]))
        mask = scenes.object_mask(ref_scene, w, h)
        t = time.perf_counter()
        chunk = 256
        ref = np.zeros((h, w, 3))
        for i in range(args.ref_spp // chunk):
            ref += render(ref_scene, chunk, 10_000 + i)
        ref /= args.ref_spp // chunk
        print(f"   reference {args.ref_spp} spp: {time.perf_counter() - t:.1f} s", flush=True)
        res: Dict[str, Any] = {"label": mat["label"], "model": mat["model"].name, "pixels": int(mask.sum()),
                               "mse": {}, "seconds": {}, "efficiency": {}}
        shown: Dict[str, np.ndarray] = {}
        for sampler, mode in CONFIGS:
            c = f"{sampler}/{mode}"
            scene = mi.load_dict(scenes.object_scene(bsdf_dict(mat, sampler), mode, w, h, 1, shape=mat["shape"]))
            render(scene, 1, 999)  # compile
            res["mse"][c], res["seconds"][c], res["efficiency"][c] = {}, {}, {}
            for spp in spps:
                errs, secs = [], []
                for s in range(args.seeds):
                    t = time.perf_counter()
                    img = render(scene, spp, 1 + s)
                    secs.append(time.perf_counter() - t)
                    errs.append(float(np.mean((img[mask] - ref[mask]) ** 2)))
                    if spp == show_spp and s == 0:
                        shown[c] = img
                mse, sec = float(np.mean(errs)), float(np.mean(secs))
                res["mse"][c][str(spp)] = mse
                res["seconds"][c][str(spp)] = sec
                res["efficiency"][c][str(spp)] = 1.0 / (mse * sec / (w * h * spp))
                print(f"   {c:13s} spp {spp:4d}: MSE {mse:.3e}  {sec:.2f} s", flush=True)
        res["timing_us"] = time_sampling(mat, args.timing_n, 3)
        print(f"   per-sample timing (us): {res['timing_us']}", flush=True)
        # images: reference and the four configurations, error maps below
        exposure = 1.0 / max(np.percentile(ref[mask], 99), 1e-6)
        escale = float(np.percentile(np.abs(shown["own/bsdf"] - ref).mean(axis=2)[mask], 99))
        top = [tonemap(ref, exposure)] + [tonemap(shown[f"{a}/{b}"], exposure) for a, b in CONFIGS]
        bottom = [np.zeros_like(ref)] + [error_map(shown[f"{a}/{b}"], ref, escale) for a, b in CONFIGS]
        gap = np.ones((h, 2, 3))
        row = lambda ims: np.concatenate(sum([[im, gap] for im in ims], [])[:-1], axis=1)  # noqa: E731
        grid = np.concatenate([row(top), np.ones((2, row(top).shape[1], 3)), row(bottom)], axis=0)
        write_png(out / f"{key}.png", grid)
        results[key] = res

    total = time.perf_counter() - t_start
    svg_plot(results, spps, out / "mse-vs-spp.svg")
    svg_plot(results, spps, out / "mse-vs-time.svg", by_time=True)
    meta = {"width": w, "height": h, "spp": spps, "seeds": args.seeds, "ref_spp": args.ref_spp,
            "show_spp": show_spp, "total_seconds": total, "mitsuba": mi.__version__,
            "diffbsdf": diffbsdf.__version__, "threads": diffbsdf.available_threads()}
    (out / "results.json").write_text(json.dumps({"meta": meta, "materials": results}, indent=1) + "\n")
    (out / "results.md").write_text(markdown(results, meta))
    print(f"total {total:.0f} s; wrote {out}")
    return 0


def markdown(results: Dict[str, Any], meta: Dict[str, Any]) -> str:
    spps = meta["spp"]
    lines = [f"MSE over the object's pixels against a {meta['ref_spp']}-spp reference (material's own "
             f"sampler, MIS), mean of {meta['seeds']} renders; {meta['width']}x{meta['height']}, "
             f"Mitsuba {meta['mitsuba']} llvm_ad_rgb, `direct` integrator.", ""]
    head = "| material | sampler | " + " | ".join(f"MSE {s} spp" for s in spps) + \
        f" | s / render at {spps[-1]} spp | efficiency at {spps[-1]} spp | rel. efficiency |"
    lines += [head, "|" + "---|" * (len(spps) + 5)]
    for k, r in results.items():
        for mode in ("bsdf", "mis"):
            own_eff = r["efficiency"][f"own/{mode}"][str(spps[-1])]
            for sampler in ("own", "learned"):
                c = f"{sampler}/{mode}"
                name = ("material's own" if sampler == "own" else "learned") + (", BSDF only" if mode == "bsdf" else ", MIS")
                eff = r["efficiency"][c][str(spps[-1])]
                lines.append(f"| {k} | {name} | " + " | ".join(f"{r['mse'][c][str(s)]:.3g}" for s in spps)
                             + f" | {r['seconds'][c][str(spps[-1])]:.2f} | {eff:.3g} | {eff / own_eff:.2f} |")
    lines += ["", "Time per call inside Mitsuba (one batch of wavefront size, best of 3, microseconds per "
              "sample; `sample` includes the nested BSDF's eval for the weight):", "",
              "| material | own sample | learned sample | own pdf | learned pdf |", "|---|---|---|---|---|"]
    for k, r in results.items():
        t = r["timing_us"]
        lines.append(f"| {k} | {t['own_sample_us']:.3f} | {t['learned_sample_us']:.3f} | "
                     f"{t['own_pdf_us']:.3f} | {t['learned_pdf_us']:.3f} |")
    lines += ["", f"Whole command: {meta['total_seconds']:.0f} s ({meta['threads']} threads)."]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    sys.exit(main())
