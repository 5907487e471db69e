"""Mitsuba 3 plugin: a BSDF ``"diffbsdf"`` that samples with a diffbsdf model and
evaluates with a nested Mitsuba BSDF.

    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")          # or "scalar_rgb"
    import diffbsdf.mitsuba_bsdf as dm
    dm.register()                           # after mi.set_variant; once per variant
    bsdf = mi.load_dict({
        "type": "diffbsdf",
        "model": "models/conductor-ggx-a0.3-cu-disk.dbsdf",
        "bsdf": {"type": "roughconductor", "distribution": "ggx", "alpha": 0.3, "material": "Cu"},
        # optional: "steps": 4 (Euler steps; default the model's), "eta": 1.5 (relative IOR
        # reported for transmitted samples; default the nested BSDF's `eta` parameter, else 1)
    })

Conventions (see ``docs/rendering.md``):

- Mitsuba's ``si.wi`` is in the local shading frame and points away from the surface:
  it is diffbsdf's ``wi``; ``BSDFSample3f.wo`` is diffbsdf's ``wo``; both PDFs are per
  unit solid angle.
- Mitsuba's ``eval`` includes the cosine foreshortening ``|cos theta_o|``; ``sample``
  returns ``weight = eval(wo) / pdf`` (the nested BSDF's value, this model's PDF).
- Disk models (BRDFs) are defined for ``wi.z >= 0``: for ``wi.z < 0`` the plugin mirrors
  ``wi`` and the sampled ``wo`` through the surface (``z -> -z``), as Mitsuba's
  ``twosided`` does; a one-sided nested BSDF then evaluates to 0 there, as it would on
  its own. ``pdf(wi, wo)`` is 0 when ``wi`` and ``wo`` are on different sides.
- Sphere models cover both sides and transmission; a sample with ``wo.z * wi.z < 0`` is
  reported as the nested BSDF's transmission component with ``eta`` the relative IOR
  (``eta`` for ``wi.z > 0``, ``1/eta`` below), reflection with ``eta = 1``.
- ``ctx.component`` / ``ctx.type_mask`` are honoured by ``eval`` (the nested BSDF) but
  not by sampling: the model samples the whole BSDF.

In the LLVM/CUDA variants the plugin is called with whole wavefronts: set
``drjit.JitFlag.SymbolicLoops`` and ``drjit.JitFlag.SymbolicCalls`` off (``wavefront()``
does that) before rendering, since the model runs in native code outside Dr.Jit's traces.
"""

from __future__ import annotations

import os
from typing import Any, Optional, Tuple

import numpy as np

from . import Model

try:
    import drjit as dr
    import mitsuba as mi
except ImportError as e:  # pragma: no cover - the test environment installs mitsuba
    raise ImportError(
        "diffbsdf.mitsuba_bsdf needs Mitsuba 3 (`pip install mitsuba`)"
    ) from e


def wavefront() -> None:
    """Turns off Dr.Jit's symbolic loops and calls so that Python BSDFs see evaluated arrays."""
    dr.set_flag(dr.JitFlag.SymbolicLoops, False)
    dr.set_flag(dr.JitFlag.SymbolicCalls, False)


def _is_scalar() -> bool:
    return mi.variant().startswith("scalar")


def _to_np(v: Any, cols: int, n: int) -> np.ndarray:
    """A Mitsuba vector (width 1 or n) as a C-contiguous float32 (n, cols) array."""
    if _is_scalar():
        a = np.asarray([float(v[i]) for i in range(cols)], dtype=np.float32)[None, :]
    else:
        a = np.asarray(v.numpy(), dtype=np.float32).reshape(cols, -1).T
    if a.shape[0] != n:
        a = np.broadcast_to(a, (n, cols))
    return np.ascontiguousarray(a, dtype=np.float32)


def _mask_np(active: Any, n: int) -> np.ndarray:
    if isinstance(active, (bool, np.bool_)):
        return np.full(n, bool(active))
    if _is_scalar():
        return np.full(n, bool(active))
    a = np.asarray(active.numpy(), dtype=bool).reshape(-1)
    return np.broadcast_to(a, (n,)) if a.shape[0] != n else a


def _vec3(a: np.ndarray) -> Any:
    if _is_scalar():
        return mi.Vector3f(float(a[0, 0]), float(a[0, 1]), float(a[0, 2]))
    return mi.Vector3f(np.ascontiguousarray(a.T))


def _float(a: np.ndarray) -> Any:
    return mi.Float(float(a[0])) if _is_scalar() else mi.Float(np.ascontiguousarray(a))


def _uint(a: np.ndarray) -> Any:
    return mi.UInt32(int(a[0])) if _is_scalar() else mi.UInt32(np.ascontiguousarray(a, np.uint32))


def _bool(a: np.ndarray) -> Any:
    return mi.Bool(bool(a[0])) if _is_scalar() else mi.Bool(np.ascontiguousarray(a, bool))


def _width(*vs: Any) -> int:
    if _is_scalar():
        return 1
    return max(dr.width(v) for v in vs)


def _resolve(path: str) -> str:
    if os.path.exists(path):
        return path
    resolved = str(mi.file_resolver().resolve(path))
    if os.path.exists(resolved):
        return resolved
    raise FileNotFoundError(f"diffbsdf: model file {path!r} not found")


_CLASSES: dict = {}


def bsdf_class() -> type:
    """The plugin class for the current Mitsuba variant (``mi.BSDF`` differs per variant)."""
    variant = mi.variant()
    if variant not in _CLASSES:
        _CLASSES[variant] = _make_class()
    return _CLASSES[variant]


def _make_class() -> type:
    class DiffBSDF(mi.BSDF):  # type: ignore[misc]
        """Samples with a diffbsdf model, evaluates with the nested BSDF."""

        def __init__(self, props: "mi.Properties") -> None:
            mi.BSDF.__init__(self, props)
            keys = set(props.keys())
            if "bsdf" not in keys:
                raise ValueError('diffbsdf: a nested BSDF is required ("bsdf": {...})')
            if "model" not in keys:
                raise ValueError('diffbsdf: a model is required ("model": "path/to/x.dbsdf")')
            self.nested = props.get("bsdf")
            if not isinstance(self.nested, mi.BSDF):
                raise TypeError('diffbsdf: "bsdf" must be a BSDF')
            model = props.get("model")
            self.model_path = str(model)
            self.model = Model.load(_resolve(self.model_path))
            self.steps: Optional[int] = int(props.get("steps")) if "steps" in keys else None
            if self.steps is not None and self.steps < 1:
                raise ValueError(f"diffbsdf: steps must be >= 1, got {self.steps}")
            # Disk and half-vector models sample the upper hemisphere only.
            self.disk = self.model.domain in ("disk", "half-vector")
            # Models declared for wi above the surface only (every disk model, a BRDF on the
            # sphere) see wi mirrored into the upper hemisphere, as `twosided` does.
            self.mirror = self.model.incident_range == "upper_hemisphere"
            self.eta = float(props.get("eta")) if "eta" in keys else self._nested_eta()
            self.m_flags = self.nested.flags()
            self.m_components = [self.nested.flags(i) for i in range(self.nested.component_count())]
            self._refl_comp, self._trans_comp = self._component_indices()

        def _nested_eta(self) -> float:
            try:
                params = mi.traverse(self.nested)
                if "eta" in params.keys():
                    eta = params["eta"]
                    return float(eta[0]) if not _is_scalar() else float(eta)
            except (RuntimeError, TypeError, KeyError, IndexError):
                pass
            return 1.0

        def _component_indices(self) -> Tuple[int, int]:
            refl, trans = 0, 0
            for i, f in enumerate(self.m_components):
                if mi.has_flag(f, mi.BSDFFlags.Reflection):
                    refl = i
                    break
            for i, f in enumerate(self.m_components):
                if mi.has_flag(f, mi.BSDFFlags.Transmission):
                    trans = i
                    break
            return refl, trans

        # -- helpers ---------------------------------------------------------------------
        def _model_side(self, wi: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
            """wi as the model sees it and the per-row z sign to undo (mirrored below the
            surface for models declared for the upper hemisphere only)."""
            sign = np.ones(wi.shape[0], dtype=np.float32)
            if self.mirror:
                sign = np.where(wi[:, 2] < 0, np.float32(-1), np.float32(1)).astype(np.float32)
                wi = wi.copy()
                wi[:, 2] *= sign
            return wi, sign

        def _pdf_np(self, wi: np.ndarray, wo: np.ndarray, act: np.ndarray) -> np.ndarray:
            wi_m, sign = self._model_side(wi)
            wo_m = wo.copy()
            wo_m[:, 2] *= sign
            ok = act.copy()
            if self.disk:
                ok &= wo_m[:, 2] > 0
            wi_m[~ok] = 0.0  # the kernel answers 0 for wi = 0
            return np.where(ok, self.model.pdf(wi_m, wo_m, self.steps), np.float32(0)).astype(np.float32)

        # -- mi.BSDF interface -------------------------------------------------------------
        def sample(self, ctx, si, sample1, sample2, active=True):  # type: ignore[no-untyped-def]
            n = _width(si.wi, sample2)
            wi = _to_np(si.wi, 3, n)
            u = _to_np(sample2, 2, n)
            act = _mask_np(active, n)
            wi_m, sign = self._model_side(wi)
            wi_m[~act] = 0.0
            wo, pdf, valid = self.model.sample(wi_m, u, self.steps)
            wo[:, 2] *= sign
            valid &= act
            refl = wo[:, 2] * wi[:, 2] > 0
            eta_t = np.where(wi[:, 2] > 0, self.eta, 1.0 / self.eta).astype(np.float32)
            eta = np.where(refl, np.float32(1), eta_t).astype(np.float32)
            comp = np.where(refl, self._refl_comp, self._trans_comp).astype(np.uint32)
            types = np.asarray([int(f) for f in self.m_components], dtype=np.uint32)
            stype = types[comp] if len(types) else np.zeros(n, np.uint32)

            bs = dr.zeros(mi.BSDFSample3f) if _is_scalar() else dr.zeros(mi.BSDFSample3f, n)
            bs.wo = _vec3(wo)
            bs.pdf = _float(np.where(valid, pdf, np.float32(0)).astype(np.float32))
            bs.eta = _float(eta)
            bs.sampled_type = _uint(stype)
            bs.sampled_component = _uint(comp)
            ok = _bool(valid)
            value = self.nested.eval(ctx, si, bs.wo, ok)
            weight = dr.select(ok & (bs.pdf > 0), value / dr.maximum(bs.pdf, 1e-30), 0.0)
            return bs, mi.Spectrum(weight)

        def eval(self, ctx, si, wo, active=True):  # type: ignore[no-untyped-def]
            return self.nested.eval(ctx, si, wo, active)

        def pdf(self, ctx, si, wo, active=True):  # type: ignore[no-untyped-def]
            n = _width(si.wi, wo)
            p = self._pdf_np(_to_np(si.wi, 3, n), _to_np(wo, 3, n), _mask_np(active, n))
            return _float(p)

        def eval_pdf(self, ctx, si, wo, active=True):  # type: ignore[no-untyped-def]
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def traverse(self, callback):  # type: ignore[no-untyped-def]
            self.nested.traverse(callback)

        def parameters_changed(self, keys):  # type: ignore[no-untyped-def]
            pass

        def to_string(self) -> str:
            return (
                f"DiffBSDF[\n  model = {self.model!r},\n  path = {self.model_path!r},\n"
                f"  steps = {self.steps},\n  eta = {self.eta},\n  nested = {self.nested}\n]"
            )

    return DiffBSDF


def register(name: str = "diffbsdf") -> None:
    """Registers the plugin for the current Mitsuba variant (call after ``mi.set_variant``)."""
    cls = bsdf_class()
    mi.register_bsdf(name, lambda props: cls(props))
