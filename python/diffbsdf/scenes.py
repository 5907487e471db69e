"""Small Mitsuba 3 test scenes built in code (no downloads): a procedural environment,
an object on a ground plane, and the integrator settings that isolate BSDF sampling."""

from __future__ import annotations

from typing import Any, Dict, Optional

import numpy as np

import mitsuba as mi


def sky_envmap(width: int = 128, height: int = 64) -> np.ndarray:
    """An equirectangular RGB sky (float32, height x width x 3): a blue-to-white gradient, a
    darker ground half, a soft warm "sun" (peak ~40), a cool fill light and coloured bands
    in azimuth, so that glossy reflections show structure at every scale."""
    v, u = np.meshgrid(
        (np.arange(height) + 0.5) / height, (np.arange(width) + 0.5) / width, indexing="ij"
    )
    theta = v * np.pi  # 0 = up (Mitsuba's envmap: +y up)
    phi = u * 2 * np.pi
    up = np.cos(theta)
    sky = np.where(up[..., None] > 0, 0.35 + 0.65 * (1 - up[..., None]) * np.float32([0.9, 0.95, 1.0]), 0.0)
    sky = sky * np.float32([0.55, 0.7, 1.0]) + np.where(up[..., None] > 0, 0.0, np.float32([0.25, 0.22, 0.18]))
    bands = 0.25 * (1 + np.sin(6 * phi))[..., None] * np.float32([1.0, 0.4, 0.2]) * (np.abs(up) < 0.3)[..., None]

    def lobe(th0: float, ph0: float, sharp: float, color: Any) -> np.ndarray:
        d = np.stack([np.sin(theta) * np.cos(phi), np.cos(theta), np.sin(theta) * np.sin(phi)], -1)
        c = np.float32([np.sin(th0) * np.cos(ph0), np.cos(th0), np.sin(th0) * np.sin(ph0)])
        return np.exp(sharp * (d @ c - 1))[..., None] * np.float32(color)

    sun = lobe(np.radians(50), np.radians(100), 60.0, [40.0, 34.0, 26.0])
    fill = lobe(np.radians(70), np.radians(250), 8.0, [0.6, 1.2, 2.0])
    return np.ascontiguousarray((sky + bands + sun + fill).astype(np.float32))


def envmap(width: int = 128, height: int = 64) -> Dict[str, Any]:
    return {"type": "envmap", "bitmap": mi.Bitmap(sky_envmap(width, height))}


def integrator(mode: str) -> Dict[str, Any]:
    """``"bsdf"``: Mitsuba's ``direct`` integrator with BSDF samples only (its MIS weight is
    then 1, so the BSDF sampler alone carries the estimate); ``"mis"``: one emitter and
    one BSDF sample per pixel sample, combined by the balance heuristic."""
    if mode == "bsdf":
        return {"type": "direct", "emitter_samples": 0, "bsdf_samples": 1}
    if mode == "mis":
        return {"type": "direct", "emitter_samples": 1, "bsdf_samples": 1}
    raise ValueError(f"mode must be 'bsdf' or 'mis', got {mode!r}")


def object_scene(
    bsdf: Dict[str, Any],
    mode: str,
    width: int = 128,
    height: int = 96,
    spp: int = 16,
    shape: str = "sphere",
    ground: bool = True,
    env: Optional[Dict[str, Any]] = None,
) -> Dict[str, Any]:
    """An object (``sphere`` or a tilted ``rectangle`` window) on a diffuse ground plane."""
    T = mi.ScalarTransform4f
    scene: Dict[str, Any] = {
        "type": "scene",
        "integrator": integrator(mode),
        "sensor": {
            "type": "perspective",
            "fov": 32,
            "to_world": T().look_at(origin=[0, 1.3, 4.2], target=[0, 0.05, 0], up=[0, 1, 0]),
            "film": {
                "type": "hdrfilm",
                "width": width,
                "height": height,
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
            "sampler": {"type": "independent", "sample_count": spp},
        },
        "env": env if env is not None else envmap(),
    }
    if shape == "sphere":
        scene["object"] = {"type": "sphere", "radius": 0.8, "bsdf": bsdf}
    elif shape == "rectangle":
        scene["object"] = {
            "type": "rectangle",
            "to_world": T().translate([0, 0.1, 0]).rotate([0, 1, 0], 25).rotate([1, 0, 0], -15).scale(0.9),
            "bsdf": bsdf,
        }
    else:
        raise ValueError(f"unknown shape {shape!r}")
    if ground:
        scene["ground"] = {
            "type": "rectangle",
            "to_world": T().translate([0, -0.8, 0]).rotate([1, 0, 0], -90).scale(6),
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.35, 0.35, 0.35]}},
        }
    return scene


def object_mask(scene: Any, width: int, height: int) -> np.ndarray:
    """Boolean (height, width) mask of the pixels whose centre sees the object."""
    sensor = scene.sensors()[0]
    ys, xs = np.meshgrid((np.arange(height) + 0.5) / height, (np.arange(width) + 0.5) / width, indexing="ij")
    pos = mi.Point2f(np.ascontiguousarray(xs.ravel(), np.float32), np.ascontiguousarray(ys.ravel(), np.float32))
    ray, _ = sensor.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5, 0.5))
    si = scene.ray_intersect(ray)
    objects = [s for s in scene.shapes() if s.id() == "object"]
    if not objects:
        raise RuntimeError("scene has no shape with id 'object'")
    hit = np.asarray(si.is_valid().numpy(), bool)
    ground = [s for s in scene.shapes() if s.id() == "ground"]
    if ground:
        # the ground is the only other shape: a pixel sees the object if it sees a hit
        # that is not on the ground plane (y > -0.8 + eps)
        y = np.asarray(si.p.y.numpy())
        return (hit & (y > -0.79)).reshape(height, width)
    return hit.reshape(height, width)
