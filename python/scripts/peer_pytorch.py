#!/usr/bin/env python3
"""Peer benchmark: the diffbsdf kernel next to a plain PyTorch implementation of the same
model, timed in the same run.

The PyTorch side is the model as a deep-learning framework writes it (`docs/math.md`):
batched matrix products over chunks of samples, float32, ``torch.no_grad`` for the
direction only, ``torch.func`` Jacobians (``vmap(jacfwd(...))`` of the velocity net) for
the per-step determinants of the direction with its PDF, and a batched Newton solve per
Euler step (the algorithm of `docs/math.md` §8) for the PDF of a given direction. It reads
the weight blob itself with numpy, following `docs/blob-format.md`, independently of the
kernel's reader. It follows `docs/math.md` in everything (encoding recurrence, Giles'
quantile, the inverse's four starts and line search) except SiLU, which is PyTorch's
``F.silu`` (library ``exp``) rather than the kernel's polynomial ``exp_poly`` (7): the two
differ by float rounding, which the check's tolerances cover.

Before timing anything, the script checks that both sides compute the same thing on the
same inputs (``--check-samples`` rows): directions (``sample_direction`` and ``sample``)
within ``--dir-tol`` (absolute, on unit vectors); the PDF of ``pdf`` (the kernel's sampled
directions fed to both sides) within ``--pdf-tol`` relative; the PDF of ``sample`` within
``--pdf-tol`` relative as a density in flow coordinates, pdf_w / m(wo) (see ``check``);
all on the rows both sides find valid, with at most ``--max-mismatch`` (a fraction) of
rows valid on one side only. If any check fails it exits with status 1 and times nothing.

Then it times the three entry points, ``sample_direction`` (direction only), ``sample``
(direction and PDF) and ``pdf`` (PDF of a given direction), at each thread count of
``--threads``: the kernel through the ``diffbsdf`` package with ``threads=n`` (one call on
the whole batch), PyTorch with ``torch.set_num_threads(n)`` (chunks of ``--chunk`` rows).
Each figure is the best of ``--repeats`` runs. Inputs: ``wi`` uniform in solid angle over
the model's incident range, ``u`` uniform; the ``pdf`` rows are valid samples of the same
model. Output: a markdown table per model.

Run from the repository root, in the project's virtual environment with ``diffbsdf`` and
``torch`` installed (``pip install torch``)::

    target/pyvenv/bin/python python/scripts/peer_pytorch.py
    target/pyvenv/bin/python python/scripts/peer_pytorch.py models/conductor-ggx-a0.3-cu-disk.dbsdf \\
        --samples 262144 --repeats 5 --threads 1,2
    target/pyvenv/bin/python python/scripts/peer_pytorch.py --check-only    # the check alone

The default blobs are the rough-copper disk (3x32, N = 4) and sphere (4x32, N = 8) models.
With the defaults (131072 rows, best of 3, 1 and 2 threads) a run takes a few minutes,
most of it in PyTorch's ``pdf``. Timings are only comparable within one run, on an
otherwise idle machine.
"""

from __future__ import annotations

import argparse
import math
import pathlib
import struct
import sys
import time
import warnings
import zlib
from dataclasses import dataclass
from typing import Callable, List, Optional, Sequence, Tuple

import numpy as np
import torch
import torch.nn.functional as F
from torch.func import jacfwd, vmap

import diffbsdf

# torch's forward-mode autodiff loads its decompositions through torch.jit.script, which
# warns about its own deprecation on first use; nothing here calls it.
warnings.filterwarnings("ignore", r"`torch.jit.script` is deprecated", FutureWarning)

ROOT = pathlib.Path(__file__).resolve().parents[2]
DEFAULT_BLOBS = [
    ROOT / "models" / "conductor-ggx-a0.3-cu-disk.dbsdf",
    ROOT / "models" / "conductor-ggx-a0.3-cu-sphere.dbsdf",
]

# ---------------------------------------------------------------------------------------
# Constants of `diffbsdf::spec` (src/spec.rs) that enter the math below.
# ---------------------------------------------------------------------------------------
MAX_STEPS = 256
MAX_WIDTH, MAX_LAYERS, MAX_FREQS = 1024, 16, 16
UNIT_TOLERANCE = 1e-3
NORMAL_INCIDENCE_RHO = 1e-12
LN_SCALE_MIN = -9.21034
LN_SCALE_MAX = math.log(10.0)
GAUSSIAN_TAIL_MIN = 2.0**-40
LN_INV_SQRT_2PI = -0.9189385
LN_4PI = 2.5310243
ERFINV_BRANCH_W = 5.0
ERFINV_CENTRAL_SHIFT = 2.5
ERFINV_CENTRAL = [
    2.8102264e-8, 3.4327394e-7, -3.5233877e-6, -4.3915065e-6, 2.1858087e-4,
    -1.253725e-3, -4.1776816e-3, 0.24664073, 1.5014094,
]
ERFINV_TAIL_SHIFT = 3.0
ERFINV_TAIL = [
    -2.0021426e-4, 1.0095056e-4, 1.3493432e-3, -3.6734284e-3, 5.7395077e-3,
    -7.6224613e-3, 9.4388705e-3, 1.001674, 2.8329768,
]
NEWTON_MAX_ITERS = 32
LINE_SEARCH_HALVINGS = 8
NEWTON_TOL = 1e-6
DET_REUSE_TOL = 1e-7

DISK, SPHERE, EQUATORIAL = 0, 1, 2
DOMAIN_NAMES = {DISK: "disk", SPHERE: "sphere", EQUATORIAL: "equatorial"}
FLAG_ISOTROPIC, FLAG_UPPER_HEMISPHERE = 1, 2

# ---------------------------------------------------------------------------------------
# The blob (docs/blob-format.md), read with numpy.
# ---------------------------------------------------------------------------------------
HEADER = struct.Struct("<8sHBBBBHBBHBBHII32s")  # 64 bytes
assert HEADER.size == 64


@dataclass
class Layer:
    weight: np.ndarray  # (outputs, inputs), float32
    bias: np.ndarray  # (outputs,), float32


@dataclass
class Blob:
    domain: int
    precision: str
    base: Tuple[int, int, int]  # (frequencies, width, hidden layers)
    velocity: Tuple[int, int, int]
    default_steps: int
    isotropic: bool
    upper_hemisphere_only: bool
    name: str
    base_layers: List[Layer]
    velocity_layers: List[Layer]

    @property
    def features(self) -> int:
        return 2 if self.domain == DISK else 3


def encoding_len(freqs: int) -> int:
    return 3 + 6 * freqs


def layer_sizes(inputs: int, width: int, hidden: int, outputs: int) -> List[Tuple[int, int]]:
    """(inputs, outputs) of each dense layer of a net: `hidden` SiLU layers, a readout."""
    return [(inputs if i == 0 else width, width) for i in range(hidden)] + [(width, outputs)]


def read_blob(data: bytes) -> Blob:
    """Validates and splits a blob in the order of docs/blob-format.md, "Errors"."""
    if len(data) < 64 + 4:
        raise ValueError("Truncated: shorter than the header")
    (magic, version, domain, precision, activation, bf, bw, bl, vf, vw, vl, name_len,
     default_steps, param_count, flags, name) = HEADER.unpack_from(data, 0)
    if magic != b"DIFFBSDF":
        raise ValueError("BadMagic")
    if version != 1:
        raise ValueError(f"UnsupportedVersion({version})")
    if precision not in (0, 1):
        raise ValueError(f"UnknownPrecision({precision})")
    size = 4 if precision == 0 else 2
    total = 64 + param_count * size + 4
    if len(data) < total:
        raise ValueError(f"Truncated: needed {total} bytes, got {len(data)}")
    if len(data) > total:
        raise ValueError(f"TrailingBytes: expected {total} bytes, got {len(data)}")
    (stored,) = struct.unpack_from("<I", data, total - 4)
    computed = zlib.crc32(data[: total - 4]) & 0xFFFFFFFF
    if stored != computed:
        raise ValueError(f"ChecksumMismatch: stored {stored:#010x}, computed {computed:#010x}")
    if domain not in DOMAIN_NAMES:
        raise ValueError(f"UnknownDomain({domain})")
    if activation != 0:
        raise ValueError(f"UnknownActivation({activation})")
    if flags & ~(FLAG_ISOTROPIC | FLAG_UPPER_HEMISPHERE):
        raise ValueError("BadHeader: unknown flag bits are set")
    for f, w, l in ((bf, bw, bl), (vf, vw, vl)):
        if not 1 <= w <= MAX_WIDTH or not 1 <= l <= MAX_LAYERS or f > MAX_FREQS:
            raise ValueError("BadHeader: net shape out of range")
    if bf > vf:
        raise ValueError("BadHeader: base net has more frequencies than the velocity net")
    if not 1 <= default_steps <= MAX_STEPS:
        raise ValueError("BadHeader: default steps out of range")
    if name_len > 32:
        raise ValueError("BadHeader: name longer than 32 bytes")
    try:
        name_str = name[:name_len].decode("utf-8")
    except UnicodeDecodeError:
        raise ValueError("BadHeader: name is not UTF-8") from None

    features = 2 if domain == DISK else 3
    base_sizes = layer_sizes(encoding_len(bf), bw, bl, 4)
    vel_sizes = layer_sizes(features + 1 + encoding_len(vf), vw, vl, 2)
    implied = sum(o * (i + 1) for i, o in base_sizes + vel_sizes)
    if implied != param_count:
        raise ValueError(f"ParamCountMismatch: declared {param_count}, shape implies {implied}")
    dtype = "<f4" if precision == 0 else "<f2"
    params = np.frombuffer(data, dtype=dtype, count=param_count, offset=64).astype(np.float32)
    if not np.all(np.isfinite(params)):
        raise ValueError(f"NonFiniteWeight at {int(np.argmin(np.isfinite(params)))}")

    pos = 0

    def take(sizes: List[Tuple[int, int]]) -> List[Layer]:
        nonlocal pos
        layers = []
        for i, o in sizes:
            w = params[pos : pos + o * i].reshape(o, i)  # row by row: W[out][in]
            pos += o * i
            b = params[pos : pos + o]
            pos += o
            layers.append(Layer(w.copy(), b.copy()))
        return layers

    base_layers = take(base_sizes)
    velocity_layers = take(vel_sizes)
    assert pos == param_count
    return Blob(
        domain=domain,
        precision="f32" if precision == 0 else "f16",
        base=(bf, bw, bl),
        velocity=(vf, vw, vl),
        default_steps=default_steps,
        isotropic=bool(flags & FLAG_ISOTROPIC),
        upper_hemisphere_only=bool(flags & FLAG_UPPER_HEMISPHERE) or domain == DISK,
        name=name_str,
        base_layers=base_layers,
        velocity_layers=velocity_layers,
    )


# ---------------------------------------------------------------------------------------
# The model in PyTorch (docs/math.md; equation numbers in brackets).
# ---------------------------------------------------------------------------------------
TAU = 2.0 * math.pi


def rows_max(a: torch.Tensor) -> torch.Tensor:
    """The max norm ||a||_inf of each row of an (n, 2) tensor."""
    return a.abs().amax(dim=-1)


def wrap(phi: torch.Tensor) -> torch.Tensor:
    """(21): phi into [-pi, pi)."""
    return phi - TAU * torch.floor((phi + math.pi) * (1.0 / TAU))


def horner(coeffs: Sequence[float], s: torch.Tensor) -> torch.Tensor:
    """(29)"""
    p = torch.full_like(s, coeffs[0])
    for c in coeffs[1:]:
        p = c + p * s
    return p


def normal_quantile(u: torch.Tensor) -> torch.Tensor:
    """(28): Giles' single-precision erfinv, evaluated from the tail probability."""
    lower = u < 0.5
    q = torch.where(lower, u, 1.0 - u).clamp(GAUSSIAN_TAIL_MIN, 0.5)
    a = 1.0 - 2.0 * q
    w = -torch.log((4.0 * q) * (1.0 - q))
    central = horner(ERFINV_CENTRAL, w - ERFINV_CENTRAL_SHIFT)
    tail = horner(ERFINV_TAIL, torch.sqrt(w) - ERFINV_TAIL_SHIFT)
    p = torch.where(w < ERFINV_BRANCH_W, central, tail)
    z = (math.sqrt(2.0) * p) * a
    return torch.where(lower, -z, z)


def ln_normal(z: torch.Tensor) -> torch.Tensor:
    """(31)"""
    return (-0.5 * z) * z + LN_INV_SQRT_2PI


class TorchFlow:
    """The model of one blob: conditioning, Euler steps, Jacobians, exact inverse."""

    def __init__(self, blob: Blob) -> None:
        self.blob = blob
        self.domain = blob.domain
        t = torch.from_numpy  # float32 arrays owned by the blob
        self.base = [(t(l.weight), t(l.bias)) for l in blob.base_layers]
        first, *rest = blob.velocity_layers
        nf = blob.features
        self.w_x = t(first.weight[:, :nf].copy())  # feature columns
        self.w_t = t(first.weight[:, nf].copy())  # time column
        self.w_c = t(first.weight[:, nf + 1 :].copy())  # encoding columns
        self.b_1 = t(first.bias)
        self.velocity_rest = [(t(l.weight), t(l.bias)) for l in rest]
        # v and dv/dx of one row, vectorised over rows: J[b, r, c] = d v_r / d x_c.
        self._jacobian = vmap(jacfwd(self._velocity_aux, argnums=0, has_aux=True))

    # -- conditioning on wi (docs/math.md §13, "Conditioning on wi") ---------------------
    def unit(self, w: torch.Tensor) -> Tuple[torch.Tensor, torch.Tensor]:
        """(45): the normalised rows and whether each passed."""
        l2 = (w[:, 0] * w[:, 0] + w[:, 1] * w[:, 1]) + w[:, 2] * w[:, 2]
        ok = torch.isfinite(w).all(dim=1) & ((l2 - 1.0).abs() <= UNIT_TOLERANCE)
        return w * (1.0 / torch.sqrt(l2))[:, None], ok

    def frame(self, wi: torch.Tensor) -> Tuple[torch.Tensor, torch.Tensor]:
        """(22): (cos, sin) of phi_i for an isotropic model, (1, 0) otherwise."""
        n = wi.shape[0]
        if not self.blob.isotropic:
            return torch.ones(n), torch.zeros(n)
        rho = torch.sqrt(wi[:, 0] * wi[:, 0] + wi[:, 1] * wi[:, 1])
        turn = rho > NORMAL_INCIDENCE_RHO
        inv = 1.0 / torch.where(turn, rho, torch.ones_like(rho))
        return (torch.where(turn, wi[:, 0] * inv, torch.ones_like(rho)),
                torch.where(turn, wi[:, 1] * inv, torch.zeros_like(rho)))

    @staticmethod
    def to_frame(v: torch.Tensor, c: torch.Tensor, s: torch.Tensor) -> torch.Tensor:
        """(23) L: world -> incident frame."""
        return torch.stack((c * v[:, 0] + s * v[:, 1], c * v[:, 1] - s * v[:, 0], v[:, 2]), 1)

    @staticmethod
    def to_world(v: torch.Tensor, c: torch.Tensor, s: torch.Tensor) -> torch.Tensor:
        """(23) W: incident frame -> world."""
        return torch.stack((c * v[:, 0] - s * v[:, 1], s * v[:, 0] + c * v[:, 1], v[:, 2]), 1)

    def encode(self, w: torch.Tensor) -> torch.Tensor:
        """(4), (5): [w, sin(2^k pi w), cos(2^k pi w), ...] by the double-angle recurrence."""
        parts = [w]
        s, c = torch.sin(math.pi * w), torch.cos(math.pi * w)
        for _ in range(self.blob.velocity[0]):
            parts += [s, c]
            s, c = (2.0 * s) * c, 1.0 - (2.0 * s) * s
        return torch.cat(parts, dim=1)

    def condition(self, wi: torch.Tensor):
        """Validates wi; returns (ok, (cos, sin), base parameters, W_c enc + b^1)."""
        wi, ok = self.unit(wi)
        if self.blob.upper_hemisphere_only:
            ok = ok & (wi[:, 2] >= 0.0)
        c, s = self.frame(wi)
        enc = self.encode(self.to_frame(wi, c, s))
        a = enc[:, : encoding_len(self.blob.base[0])]
        for w, b in self.base[:-1]:
            a = F.silu(F.linear(a, w, b))
        o = F.linear(a, *self.base[-1])  # (9)
        if self.domain == DISK:  # (24): mu_0, mu_1, ln sigma_0, ln sigma_1
            params = (o[:, 0:2], o[:, 2:4].clamp(LN_SCALE_MIN, LN_SCALE_MAX))
        else:  # (25): mu_theta, ln sigma, mu_phi, ln gamma
            params = (o[:, 0:3:2], o[:, 1:4:2].clamp(LN_SCALE_MIN, LN_SCALE_MAX))
        cond = F.linear(enc, self.w_c, self.b_1)  # the wi part of (11)
        return ok, (c, s), params, cond

    # -- base distribution (§6) -------------------------------------------------------------
    def base_point(self, params, u: torch.Tensor) -> torch.Tensor:
        """(26), (27)"""
        mu, ln_scale = params
        if self.domain == DISK:
            return mu + torch.exp(ln_scale) * normal_quantile(u)
        theta = mu[:, 0] + torch.exp(ln_scale[:, 0]) * normal_quantile(u[:, 0])
        gamma = torch.exp(ln_scale[:, 1])
        delta = 2.0 * torch.atan2(-torch.tanh(0.5 * gamma) * torch.cos(math.pi * u[:, 1]),
                                  torch.sin(math.pi * u[:, 1]))  # (30)
        return torch.stack((theta, mu[:, 1] + delta), 1)

    def ln_base(self, params, x0: torch.Tensor) -> torch.Tensor:
        """(32), (34)"""
        mu, ln_scale = params
        if self.domain == DISK:
            z = (x0 - mu) * torch.exp(-ln_scale)
            return ((ln_normal(z[:, 0]) + ln_normal(z[:, 1])) - ln_scale[:, 0]) - ln_scale[:, 1]
        z = (x0[:, 0] - mu[:, 0]) * torch.exp(-ln_scale[:, 0])
        gamma = torch.exp(ln_scale[:, 1])
        sh, sd = torch.sinh(0.5 * gamma), torch.sin(0.5 * (x0[:, 1] - mu[:, 1]))
        ln_wc = (torch.log(torch.sinh(gamma)) - LN_4PI) - torch.log(sh * sh + sd * sd)  # (33)
        return (ln_normal(z) - ln_scale[:, 0]) + ln_wc

    # -- domain (§4) ------------------------------------------------------------------------
    def advance(self, x: torch.Tensor, d: torch.Tensor) -> torch.Tensor:
        if self.domain == DISK:
            return x + d
        return torch.stack((x[:, 0] + d[:, 0], wrap(x[:, 1] + d[:, 1])), 1)

    def difference(self, a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
        if self.domain == DISK:
            return a - b
        return torch.stack((a[:, 0] - b[:, 0], wrap(a[:, 1] - b[:, 1])), 1)

    def direction(self, x: torch.Tensor) -> Tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """(15), (18), (53): wo' of x_N, its validity and ln m (17), (20)."""
        if self.domain == DISK:
            r2 = x[:, 0] * x[:, 0] + x[:, 1] * x[:, 1]
            z = torch.sqrt((1.0 - r2).clamp_min(0.0))
            ok = (r2 < 1.0) & (z > 0.0)
            return torch.stack((x[:, 0], x[:, 1], z), 1), ok, torch.log(z)
        theta, phi = x[:, 0], x[:, 1]
        st = torch.sin(theta)
        ok = (st > 0.0) & (theta > 0.0) & (theta < math.pi)
        a, b, c = st * torch.cos(phi), st * torch.sin(phi), torch.cos(theta)
        wo = torch.stack((a, b, c) if self.domain == SPHERE else (a, c, b), 1)
        return wo, ok, -torch.log(st)

    def point(self, wo: torch.Tensor) -> Tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """(16), (19), (54): x of a direction wo', its validity and ln m."""
        if self.domain == DISK:
            return wo[:, :2], wo[:, 2] > 0.0, torch.log(wo[:, 2])
        axis, (i, j) = (2, (0, 1)) if self.domain == SPHERE else (1, (0, 2))
        rho = torch.sqrt(wo[:, i] * wo[:, i] + wo[:, j] * wo[:, j])
        x = torch.stack((torch.atan2(rho, wo[:, axis]), torch.atan2(wo[:, j], wo[:, i])), 1)
        return x, rho > 0.0, -torch.log(torch.sin(x[:, 0]))

    # -- velocity net (§3.5) and its Jacobian (§3.6) ---------------------------------------
    def features(self, x: torch.Tensor) -> torch.Tensor:
        """(10), for one row (2,) or a batch (n, 2)."""
        if self.domain == DISK:
            return x
        phi = x[..., 1]
        return torch.stack((x[..., 0], torch.sin(phi), torch.cos(phi)), -1)

    def velocity(self, x: torch.Tensor, cond_t: torch.Tensor) -> torch.Tensor:
        """(11), (12); cond_t = W_c enc + b^1 + w_t t."""
        a = F.silu(F.linear(self.features(x), self.w_x) + cond_t)
        for w, b in self.velocity_rest[:-1]:
            a = F.silu(F.linear(a, w, b))
        return F.linear(a, *self.velocity_rest[-1])

    def _velocity_aux(self, x, cond_t):
        v = self.velocity(x, cond_t)
        return v, v

    def velocity_jacobian(self, x, cond_t) -> Tuple[torch.Tensor, torch.Tensor]:
        """v (n, 2) and J = dv/dx (n, 2, 2) by forward-mode autodiff."""
        j, v = self._jacobian(x, cond_t)
        return v, j

    @staticmethod
    def step_det(h: float, j: torch.Tensor) -> torch.Tensor:
        """(37): det(I + h J)."""
        return (1.0 + h * j[:, 0, 0]) * (1.0 + h * j[:, 1, 1]) - (h * j[:, 0, 1]) * (h * j[:, 1, 0])

    def cond_at(self, cond: torch.Tensor, k: int, h: float) -> torch.Tensor:
        t = float(np.float32(k) * np.float32(h))  # (35)
        return cond + t * self.w_t

    # -- entry points (§10) -------------------------------------------------------------------
    def sample_direction(self, wi: torch.Tensor, u: torch.Tensor, steps: int):
        """-> (wo (n, 3), valid (n,)); invalid rows are 0."""
        ok, (c, s), params, cond = self.condition(wi)
        ok = ok & ((u >= 0.0) & (u <= 1.0)).all(dim=1)
        h = float(np.float32(1.0) / np.float32(steps))
        x = self.advance(self.base_point(params, u), torch.zeros_like(u))
        for k in range(steps):
            x = self.advance(x, h * self.velocity(x, self.cond_at(cond, k, h)))  # (36)
        wo, inside, _ = self.direction(x)
        wo = self.to_world(wo, c, s)
        ok = ok & inside & torch.isfinite(wo).all(dim=1)
        return torch.where(ok[:, None], wo, 0.0), ok

    def sample(self, wi: torch.Tensor, u: torch.Tensor, steps: int):
        """-> (wo (n, 3), pdf (n,), valid (n,)); (38), with per-step Jacobian determinants."""
        ok, (c, s), params, cond = self.condition(wi)
        ok = ok & ((u >= 0.0) & (u <= 1.0)).all(dim=1)
        h = float(np.float32(1.0) / np.float32(steps))
        x0 = self.base_point(params, u)
        x = self.advance(x0, torch.zeros_like(u))
        ln_det = torch.zeros(x.shape[0])
        for k in range(steps):
            v, j = self.velocity_jacobian(x, self.cond_at(cond, k, h))
            det = self.step_det(h, j)
            ok = ok & (det > 0.0)
            ln_det = ln_det + torch.log(det)
            x = self.advance(x, h * v)
        wo, inside, ln_m = self.direction(x)
        pdf = torch.exp((self.ln_base(params, x0) - ln_det) + ln_m)
        wo = self.to_world(wo, c, s)
        ok = ok & inside & torch.isfinite(wo).all(dim=1) & torch.isfinite(pdf) & (pdf > 0.0)
        return torch.where(ok[:, None], wo, 0.0), torch.where(ok, pdf, 0.0), ok

    def pdf(self, wi: torch.Tensor, wo: torch.Tensor, steps: int) -> torch.Tensor:
        """(44): the exact inverse of every Euler step by batched Newton (§8)."""
        ok, (c, s), params, cond = self.condition(wi)
        wo, wo_ok = self.unit(wo)
        y, inside, ln_m = self.point(self.to_frame(wo, c, s))
        ok = ok & wo_ok & inside
        h = float(np.float32(1.0) / np.float32(steps))
        x = self.advance(y, torch.zeros_like(y))
        ln_det = torch.zeros(x.shape[0])
        rows = torch.nonzero(ok).squeeze(1)  # rows still being inverted
        # The velocity at the next time (43): for the last step, at the end, t = N h.
        v = torch.zeros_like(x)
        v[rows] = self.velocity(x[rows], self.cond_at(cond[rows], steps, h))
        for k in reversed(range(steps)):
            prev, det, v_prev, solved = self.invert_step(
                x[rows], v[rows], self.cond_at(cond[rows], k, h), h)
            x[rows], v[rows] = prev, v_prev
            ln_det[rows] = ln_det[rows] + torch.log(det)
            ok[rows[~solved]] = False
            rows = rows[solved]
        pdf = torch.exp((self.ln_base(params, x) - ln_det) + ln_m)
        return torch.where(ok & torch.isfinite(pdf), pdf, 0.0)

    # -- exact inverse of one Euler step (§8) ----------------------------------------------
    def residual(self, x, y, cond_t, h):
        """(39): R(x) = difference(advance(x, h v(x)), y), J, det and v at x."""
        v, j = self.velocity_jacobian(x, cond_t)
        r = self.difference(self.advance(x, h * v), y)
        return r, j, self.step_det(h, j), v

    def invert_step(self, y, v_next, cond_t, h):
        """(43): Newton from four starts in turn; -> (x, det, v, solved) per row."""
        n = y.shape[0]
        x_out, det_out, v_out = y.clone(), torch.ones(n), torch.zeros_like(y)
        solved = torch.zeros(n, dtype=torch.bool)
        todo = torch.arange(n)

        def attempt(start: torch.Tensor) -> None:
            nonlocal todo
            x, det, v, good = self.newton(start, y[todo], cond_t[todo], h)
            done = todo[good]
            x_out[done], det_out[done], v_out[done], solved[done] = x[good], det[good], v[good], True
            todo = todo[~good]

        attempt(self.advance(y, -h * v_next))  # the next time's velocity
        if todo.numel() == 0:
            return x_out, det_out, v_out, solved
        # Rarely needed: the velocity at this step's time, at y.
        v = torch.zeros_like(y)
        v[todo] = self.velocity(y[todo], cond_t[todo])
        first = self.advance(y, -h * v)
        starts: List[Callable[[torch.Tensor], torch.Tensor]] = [
            lambda i: first[i],
            lambda i: self.advance(y[i], -h * self.velocity(first[i], cond_t[i])),
            lambda i: self.advance(y[i], (-0.5 * h) * v[i]),
        ]
        for start in starts:
            if todo.numel() == 0:
                break
            attempt(start(todo))
        return x_out, det_out, v_out, solved

    def newton(self, x, y, cond_t, h):
        """(40)-(42), batched: rows leave the active set as they converge or fail."""
        n = x.shape[0]
        x_out, det_out, v_out = x.clone(), torch.ones(n), torch.zeros_like(x)
        good = torch.zeros(n, dtype=torch.bool)
        idx = torch.arange(n)  # active rows, indices into the outputs
        r, j, det, v = self.residual(x, y, cond_t, h)
        for _ in range(NEWTON_MAX_ITERS):
            if idx.numel() == 0:
                break
            # (40) where det > 0, else (41).
            a00, a01 = 1.0 + h * j[:, 0, 0], h * j[:, 0, 1]
            a10, a11 = h * j[:, 1, 0], 1.0 + h * j[:, 1, 1]
            safe = torch.where(det > 0.0, det, torch.ones_like(det))
            newton_d = torch.stack(((a11 * r[:, 0] - a01 * r[:, 1]) / safe,
                                    (a00 * r[:, 1] - a10 * r[:, 0]) / safe), 1)
            d = torch.where((det > 0.0)[:, None], newton_d, r)
            size, scale = rows_max(d), 1.0 + rows_max(x)
            finite = torch.isfinite(size)
            small = finite & (size <= NEWTON_TOL * scale)
            if small.any():  # converged: take the update, det at the returned point
                xc = self.advance(x[small], -d[small])
                dc, vc = det[small].clone(), v[small].clone()
                # where the update is about one rounding of x, R(x) stands for R(xc)
                moved = size[small] > DET_REUSE_TOL * scale[small]
                if moved.any():
                    _, _, dc[moved], vc[moved] = self.residual(
                        xc[moved], y[small][moved], cond_t[small][moved], h)
                i = idx[small]
                x_out[i], det_out[i], v_out[i], good[i] = xc, dc, vc, dc > 0.0
            go = finite & ~small
            x, y, cond_t, r, d, size, scale, idx = (
                a[go] for a in (x, y, cond_t, r, d, size, scale, idx))
            # Backtracking line search from the same x: x - d, x - d/2, ..., x - 2^-H d.
            m = idx.numel()
            norm = rows_max(r)
            lam = torch.ones(m)
            nx, nr, nj, ndet = x.clone(), r.clone(), torch.zeros(m, 2, 2), torch.zeros(m)
            nv = torch.zeros(m, 2)
            searching = torch.arange(m)
            for halving in range(LINE_SEARCH_HALVINGS + 1):
                if searching.numel() == 0:
                    break
                s = searching
                tx = self.advance(x[s], -lam[s, None] * d[s])
                tr, tj, tdet, tv = self.residual(tx, y[s], cond_t[s], h)
                take = (rows_max(tr) < norm[s]) | (halving == LINE_SEARCH_HALVINGS)
                a = s[take]
                nx[a], nr[a], nj[a], ndet[a] = tx[take], tr[take], tj[take], tdet[take]
                nv[a] = tv[take]
                lam[s[~take]] *= 0.5
                searching = s[~take]
            x, r, j, det, v = nx, nr, nj, ndet, nv
            stop = (lam * size <= NEWTON_TOL * scale) & (det > 0.0)
            if stop.any():
                i = idx[stop]
                x_out[i], det_out[i], v_out[i], good[i] = x[stop], det[stop], v[stop], True
            keep = ~stop
            x, y, cond_t, r, j, det, v, idx = (
                a[keep] for a in (x, y, cond_t, r, j, det, v, idx))
        return x_out, det_out, v_out, good


# ---------------------------------------------------------------------------------------
# Running PyTorch over chunks, and the kernel.
# ---------------------------------------------------------------------------------------
def in_chunks(fn, arrays: Sequence[np.ndarray], chunk: int, grad: bool):
    """Applies fn to torch views of `chunk` rows at a time; concatenates numpy outputs."""
    n = arrays[0].shape[0]
    outs: List[List[np.ndarray]] = []
    ctx = torch.enable_grad() if grad else torch.no_grad()
    with ctx:
        for lo in range(0, n, chunk):
            res = fn(*(torch.from_numpy(a[lo : lo + chunk]) for a in arrays))
            res = res if isinstance(res, tuple) else (res,)
            outs.append([r.detach().numpy() for r in res])
    return tuple(np.concatenate(parts) for parts in zip(*outs))


def torch_entry(flow: TorchFlow, entry: str, steps: int, chunk: int):
    """The PyTorch side of one entry point: a function of numpy arrays."""
    method = getattr(flow, entry)
    grad = entry != "sample_direction"  # the Jacobians need autodiff; the direction does not
    return lambda a, b: in_chunks(lambda x, y: method(x, y, steps), (a, b), chunk, grad)


def kernel_entry(model: "diffbsdf.Model", entry: str, steps: int, threads: Optional[int]):
    fn = getattr(model, entry)
    return lambda a, b: fn(a, b, steps=steps, threads=threads)


def random_inputs(blob: Blob, n: int, rng: np.random.Generator) -> Tuple[np.ndarray, np.ndarray]:
    """wi uniform in solid angle over the incident range (unit in f32), u uniform."""
    cos_lo = 0.0 if blob.upper_hemisphere_only else -1.0
    z = rng.uniform(cos_lo, 1.0, n)
    phi = rng.uniform(-math.pi, math.pi, n)
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    wi = np.stack((r * np.cos(phi), r * np.sin(phi), z), 1).astype(np.float32)
    u = rng.random((n, 2), dtype=np.float32)
    return np.ascontiguousarray(wi), u


def valid_pdf_rows(model, wi, u, steps, n) -> Tuple[np.ndarray, np.ndarray]:
    """(wi, wo) rows, n of them, with wo a valid sample of the model at wi."""
    wo, _, valid = model.sample(wi, u, steps=steps)
    idx = np.flatnonzero(valid)
    if idx.size == 0:
        raise RuntimeError("the model returned no valid sample")
    take = idx[np.arange(n) % idx.size]
    return np.ascontiguousarray(wi[take]), np.ascontiguousarray(wo[take])


# ---------------------------------------------------------------------------------------
# The check.
# ---------------------------------------------------------------------------------------
def measure(blob: Blob, wo: np.ndarray) -> np.ndarray:
    """m = pdf_w / pdf_x of directions, (17) / (20), in float64."""
    wo = wo.astype(np.float64)
    if blob.domain == DISK:
        return wo[:, 2]
    i, j = (0, 1) if blob.domain == SPHERE else (0, 2)
    return 1.0 / np.sqrt(wo[:, i] ** 2 + wo[:, j] ** 2)


def check(flow: TorchFlow, model, steps: int, n: int, chunk: int, args, rng) -> bool:
    """Both sides on the same inputs; prints one line per entry point, False on failure.

    `sample`'s PDFs are compared as densities in flow coordinates, pdf_w / m(wo) with each
    side's own wo: near the disk's rim (wo_z -> 0) or the sphere's poles the measure
    change m amplifies the f32 rounding differences of x_N into relative differences of
    pdf_w (a 1e-7 shift of x_N at wo_z = 0.003 changes m by 1 %). The raw pdf_w difference
    is printed too. `pdf` takes the same wo on both sides, so its pdf_w is compared directly.
    """
    wi, u = random_inputs(flow.blob, n, rng)
    ok_all = True

    def compare(what, k_valid, t_valid, pairs):
        nonlocal ok_all
        both = k_valid & t_valid
        mismatch = int(np.count_nonzero(k_valid != t_valid))
        allowed = int(args.max_mismatch * n)
        line = f"  {what:<16} valid {int(both.sum())}/{n}, "
        line += f"on one side only {mismatch} (max {allowed})"
        good = mismatch <= allowed and bool(both.any())
        for label, k, t, tol, relative in pairs:
            k, t = k[both].astype(np.float64), t[both].astype(np.float64)
            err = np.abs(k - t) / (np.abs(k) if relative else 1.0)
            err = err.reshape(err.shape[0], -1).max(axis=1)
            worst = float(err.max()) if err.size else math.nan
            med = float(np.median(err)) if err.size else math.nan
            line += f"; {label} max {worst:.1e} median {med:.1e}"
            if tol is None:
                line += " (info)"
            else:
                line += f" (tol {tol:g})"
                good = good and err.size > 0 and worst <= tol
        print(line + ("  OK" if good else "  FAILED"))
        ok_all = ok_all and good

    k_wo, k_valid = model.sample_direction(wi, u, steps=steps)
    (t_wo, t_valid) = torch_entry(flow, "sample_direction", steps, chunk)(wi, u)
    compare("sample_direction", k_valid, t_valid, [("|dwo|", k_wo, t_wo, args.dir_tol, False)])

    k_wo, k_pdf, k_valid = model.sample(wi, u, steps=steps)
    t_wo, t_pdf, t_valid = torch_entry(flow, "sample", steps, chunk)(wi, u)
    with np.errstate(divide="ignore", invalid="ignore"):
        k_pdf_x, t_pdf_x = k_pdf / measure(flow.blob, k_wo), t_pdf / measure(flow.blob, t_wo)
    compare("sample", k_valid, t_valid, [("|dwo|", k_wo, t_wo, args.dir_tol, False),
                                         ("pdf_x rel", k_pdf_x, t_pdf_x, args.pdf_tol, True),
                                         ("pdf_w rel", k_pdf, t_pdf, None, True)])

    # The PDF of the kernel's sampled directions (its valid rows), on both sides.
    k_p = model.pdf(wi, k_wo, steps=steps)
    (t_p,) = torch_entry(flow, "pdf", steps, chunk)(wi, k_wo)
    compare("pdf", k_valid & (k_p > 0), k_valid & (t_p > 0),
            [("pdf_w rel", k_p, t_p, args.pdf_tol, True)])
    return ok_all


# ---------------------------------------------------------------------------------------
# Timing.
# ---------------------------------------------------------------------------------------
def best_time(fn, a, b, repeats: int) -> float:
    best = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn(a, b)
        best = min(best, time.perf_counter() - t0)
    return best


ENTRIES = [
    ("sample_direction", "direction only"),
    ("sample", "direction + PDF"),
    ("pdf", "PDF of a direction"),
]


def benchmark(flow: TorchFlow, model, steps: int, args, rng) -> List[Tuple[str, int, float, float]]:
    n = args.samples
    wi, u = random_inputs(flow.blob, n, rng)
    pdf_wi, pdf_wo = valid_pdf_rows(model, wi, u, steps, n)
    rows = []
    for threads in args.threads:
        torch.set_num_threads(threads)
        for entry, label in ENTRIES:
            a, b = (pdf_wi, pdf_wo) if entry == "pdf" else (wi, u)
            k_fn = kernel_entry(model, entry, steps, threads)
            t_fn = torch_entry(flow, entry, steps, args.chunk)
            k_fn(a[: args.chunk], b[: args.chunk])  # warm-up (first-call costs)
            t_fn(a[: args.chunk], b[: args.chunk])
            k = n / best_time(k_fn, a, b, args.repeats)
            t = n / best_time(t_fn, a, b, args.repeats)
            rows.append((label, threads, k, t))
    return rows


def parse_threads(text: str) -> List[int]:
    out = [int(t) for t in text.split(",") if t.strip()]
    if not out or min(out) < 1:
        raise argparse.ArgumentTypeError("a comma-separated list of thread counts >= 1")
    return out


def main(argv: Optional[Sequence[str]] = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("blobs", nargs="*", type=pathlib.Path,
                   help="weight blobs (.dbsdf); none: models/conductor-ggx-a0.3-cu-{disk,sphere}")
    p.add_argument("--samples", type=int, default=131072, help="rows per timed call")
    p.add_argument("--repeats", type=int, default=3, help="timed runs per figure, best kept")
    p.add_argument("--threads", type=parse_threads, default="1,2",
                   help="comma-separated thread counts")
    p.add_argument("--steps", type=int, default=None, help="Euler steps; None: the model's")
    p.add_argument("--chunk", type=int, default=16384, help="PyTorch rows per batch")
    p.add_argument("--check-samples", type=int, default=4096, help="rows of the check")
    p.add_argument("--dir-tol", type=float, default=1e-4, help="direction tolerance")
    p.add_argument("--pdf-tol", type=float, default=1e-3, help="relative PDF tolerance")
    p.add_argument("--max-mismatch", type=float, default=1e-3,
                   help="largest fraction of rows valid on one side only")
    p.add_argument("--check-only", action="store_true", help="run the check, time nothing")
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args(argv)

    rng = np.random.default_rng(args.seed)
    print(f"diffbsdf {diffbsdf.KERNEL_VERSION}, torch {torch.__version__}, "
          f"{args.samples} rows per call, best of {args.repeats}, PyTorch chunks of {args.chunk}")
    results = []
    for path in args.blobs or DEFAULT_BLOBS:
        data = path.read_bytes()
        blob = read_blob(data)
        model = diffbsdf.Model.load(data)
        steps = args.steps or blob.default_steps
        _, vw, vl = blob.velocity
        desc = (f"{path.name}: {DOMAIN_NAMES[blob.domain]}, velocity {vl}x{vw}, N = {steps}, "
                f"{blob.precision}, {'isotropic' if blob.isotropic else 'anisotropic'}")
        print(f"\n{desc}\ncheck against the kernel ({args.check_samples} rows):")
        torch.set_num_threads(max(args.threads))
        if not check(TorchFlow(blob), model, steps, args.check_samples, args.chunk, args, rng):
            print("PyTorch and the kernel disagree: nothing timed.", file=sys.stderr)
            return 1
        if not args.check_only:
            results.append((desc, benchmark(TorchFlow(blob), model, steps, args, rng)))

    for desc, rows in results:
        print(f"\n{desc}\n")
        print("| entry point | threads | kernel samples/s | PyTorch samples/s "
              "| kernel / PyTorch |")
        print("|---|---:|---:|---:|---:|")
        for label, threads, k, t in rows:
            print(f"| {label} | {threads} | {k:,.0f} | {t:,.0f} | {k / t:.1f}x |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
