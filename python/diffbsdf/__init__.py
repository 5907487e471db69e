"""Importance-sample BSDFs with a tiny learned rectified flow (numpy batch API).

>>> import numpy as np, diffbsdf
>>> m = diffbsdf.Model.load("models/conductor-ggx-a0.3-cu-disk.dbsdf")
>>> wi = np.tile(np.float32([0.3, 0.0, 0.9539392]), (4, 1))
>>> wo, pdf, valid = m.sample(wi, np.random.default_rng(0).random((4, 2), np.float32))
>>> bool(np.allclose(m.pdf(wi, wo)[valid], pdf[valid], rtol=1e-4))
True

Conventions (``docs/math.md``): local shading frame, ``z`` the normal; ``wi`` and ``wo``
unit vectors pointing away from the surface; PDFs per unit solid angle of ``wo``.

Arrays: directions are ``(N, 3)``, random numbers ``(N, 2)``. A C-contiguous float32
ndarray is read in place (no copy). Any other real floating array (float64, float16,
non-contiguous, a list of floats) is converted once with ``numpy.ascontiguousarray(x,
dtype=float32)``. Integer, complex, bool or object arrays raise ``TypeError``; a wrong
shape or differing lengths raise ``ValueError``. Outputs are new float32 / bool arrays.

Reference materials (``Material``): the analytic and measured BSDFs a model is trained
on, with the same array conventions, to compare a learned model with its target::

    cu = diffbsdf.Material.from_spec("conductor:ggx,alpha=0.3,metal=Cu")
    f_cos = cu.eval(wi, wo)               # (N, 3) RGB f * |cos theta_o|
    wo, pdf, valid = cu.sample(wi, u3)     # u3: (N, 3), the third number picks a lobe

Threads: the GIL is released and a batch is split into contiguous chunks over
``threads`` OS threads (default: ``available_threads()``, i.e. the machine's available
parallelism; set ``Model.threads`` or pass ``threads=`` per call). Every row is
computed independently, so the result does not depend on the thread count.
"""

from __future__ import annotations

import os
from typing import Optional, Tuple, Union

import numpy as np

from ._diffbsdf import (
    KERNEL_VERSION,
    MAX_STEPS,
    BlobFormatError,
    RawMaterial,
    RawModel,
    available_threads,
)

__all__ = [
    "Model",
    "Material",
    "BlobFormatError",
    "available_threads",
    "KERNEL_VERSION",
    "MAX_STEPS",
    "as_rows",
]
__version__ = KERNEL_VERSION

PathOrBytes = Union[str, "os.PathLike[str]", bytes, bytearray, memoryview]


def as_rows(x: object, cols: int, name: str) -> np.ndarray:
    """``x`` as a C-contiguous float32 ``(N, cols)`` array, without a copy if it is one."""
    arr = x if isinstance(x, np.ndarray) else np.asarray(x)
    if arr.dtype.kind != "f":
        raise TypeError(
            f"{name}: expected a real floating array (float32 is used in place), got dtype {arr.dtype}"
        )
    if arr.ndim != 2 or arr.shape[1] != cols:
        raise ValueError(f"{name}: expected shape (N, {cols}), got {arr.shape}")
    return np.ascontiguousarray(arr, dtype=np.float32)


def _steps(steps: Optional[int]) -> Optional[int]:
    if steps is None:
        return None
    if isinstance(steps, (bool, np.bool_)) or not isinstance(steps, (int, np.integer)):
        raise TypeError(f"steps must be an int >= 1 or None, got {type(steps).__name__}")
    return int(steps)


class Model:
    """A loaded diffbsdf weight blob (any shape the kernel is compiled for)."""

    __slots__ = ("_raw", "threads")

    def __init__(self, raw: RawModel, threads: Optional[int] = None) -> None:
        self._raw = raw
        #: Threads per batch call; ``None`` means ``available_threads()``.
        self.threads: Optional[int] = threads

    @classmethod
    def load(cls, src: PathOrBytes, threads: Optional[int] = None) -> "Model":
        """Loads a blob from a file path or from its bytes.

        Raises ``BlobFormatError`` (a ``ValueError``) for bytes that are not a valid blob,
        ``OSError`` for an unreadable file, ``TypeError`` for anything else.
        """
        if isinstance(src, (bytes, bytearray, memoryview)):
            data = bytes(src)
        elif isinstance(src, (str, os.PathLike)):
            with open(src, "rb") as f:
                data = f.read()
        else:
            raise TypeError(f"Model.load takes a path or bytes, got {type(src).__name__}")
        return cls(RawModel.from_bytes(data), threads)

    # -- the model definition ------------------------------------------------------------
    @property
    def domain(self) -> str:
        """``"disk"`` or ``"half-vector"`` (BRDFs: ``wi.z >= 0`` only, sample the upper
        hemisphere), ``"sphere"`` or ``"equatorial"``."""
        return self._raw.domain

    @property
    def default_steps(self) -> int:
        """Euler steps used when ``steps=None``."""
        return self._raw.default_steps

    @property
    def isotropic(self) -> bool:
        return self._raw.isotropic

    @property
    def incident_range(self) -> str:
        """``"upper_hemisphere"`` (``wi.z >= 0`` only; other ``wi`` give invalid rows and
        PDF 0) or ``"whole_sphere"``: the ``wi`` the model was trained for."""
        return self._raw.incident_range

    @property
    def precision(self) -> str:
        """``"f32"`` or ``"f16"``: how the blob stores weights (evaluation is f32)."""
        return self._raw.precision

    @property
    def name(self) -> str:
        return self._raw.name

    @property
    def shape(self) -> Tuple[Tuple[int, int, int], Tuple[int, int, int]]:
        """``((freqs, width, hidden_layers) of the base net, the same of the velocity net)``."""
        return self._raw.shape

    def __repr__(self) -> str:
        return (
            f"diffbsdf.Model(name={self.name!r}, domain={self.domain!r}, "
            f"default_steps={self.default_steps}, isotropic={self.isotropic}, "
            f"precision={self.precision!r})"
        )

    # -- batch entry points -------------------------------------------------------------
    def sample(
        self, wi: object, u: object, steps: Optional[int] = None, threads: Optional[int] = None
    ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(wo (N,3) float32, pdf (N,) float32, valid (N,) bool)``; invalid rows are 0."""
        return self._raw.sample(
            as_rows(wi, 3, "wi"), as_rows(u, 2, "u"), _steps(steps), self._threads(threads)
        )

    def sample_direction(
        self, wi: object, u: object, steps: Optional[int] = None, threads: Optional[int] = None
    ) -> Tuple[np.ndarray, np.ndarray]:
        """``(wo (N,3) float32, valid (N,) bool)`` without PDFs (cheaper)."""
        return self._raw.sample_direction(
            as_rows(wi, 3, "wi"), as_rows(u, 2, "u"), _steps(steps), self._threads(threads)
        )

    def pdf(
        self, wi: object, wo: object, steps: Optional[int] = None, threads: Optional[int] = None
    ) -> np.ndarray:
        """``pdf (N,) float32`` of ``wo`` given ``wi``, per unit solid angle."""
        return self._raw.pdf(
            as_rows(wi, 3, "wi"), as_rows(wo, 3, "wo"), _steps(steps), self._threads(threads)
        )

    def _threads(self, threads: Optional[int]) -> Optional[int]:
        t = self.threads if threads is None else threads
        if t is not None and (isinstance(t, bool) or not isinstance(t, (int, np.integer))):
            raise TypeError(f"threads must be an int >= 1 or None, got {type(t).__name__}")
        return None if t is None else int(t)


def _check_threads(threads: Optional[int]) -> Optional[int]:
    if threads is not None and (
        isinstance(threads, bool) or not isinstance(threads, (int, np.integer))
    ):
        raise TypeError(f"threads must be an int >= 1 or None, got {type(threads).__name__}")
    return None if threads is None else int(threads)


class Material:
    """A reference material of ``diffbsdf-materials``: its BSDF, its own sampler and PDF.

    Conventions are the kernel's: local shading frame, ``z`` the normal, unit ``wi`` and
    ``wo`` pointing away from the surface, PDFs per unit solid angle. ``eval`` returns
    ``f(wi, wo) * |cos theta_o|`` per RGB channel (what Mitsuba's ``BSDF.eval`` returns);
    ``eval_luminance`` its Rec. 709 luminance. A direction that is not finite or not unit
    within the kernel's tolerance (``| |w|^2 - 1 | <= 1e-3``; it is then normalised), or a
    ``u`` outside [0, 1], gives a zero row (``valid = False`` for ``sample``).
    Computation is in float64, outputs are float32. Arrays as for ``Model``.
    """

    __slots__ = ("_raw", "threads")

    def __init__(self, raw: RawMaterial, threads: Optional[int] = None) -> None:
        self._raw = raw
        #: Threads per batch call; ``None`` means ``available_threads()``.
        self.threads: Optional[int] = threads

    @classmethod
    def from_spec(cls, spec: str, threads: Optional[int] = None) -> "Material":
        """A material from the spec of ``diffbsdf material`` / ``diffbsdf fit``, e.g.
        ``"conductor:ggx,alpha=0.3,metal=Cu"``, ``"dielectric:beckmann,alpha=0.3,eta=1.5"``,
        ``"rgl:path/file_rgb.bsdf"`` (grammar: ``materials/MATERIALS.md``).

        Raises ``ValueError`` for a spec that does not parse, ``OSError`` for an RGL file
        that cannot be read.
        """
        if not isinstance(spec, str):
            raise TypeError(f"Material.from_spec takes a str, got {type(spec).__name__}")
        return cls(RawMaterial.from_spec(spec), threads)

    @classmethod
    def rgl(cls, path: "Union[str, os.PathLike[str]]", threads: Optional[int] = None) -> "Material":
        """An RGL measured material (``*_rgb.bsdf``, Dupuy & Jakob 2018).

        Raises ``OSError`` (``FileNotFoundError``) for an unreadable file, ``ValueError``
        for a file that is not a valid RGL tensor file.
        """
        if not isinstance(path, (str, os.PathLike)):
            raise TypeError(f"Material.rgl takes a path, got {type(path).__name__}")
        return cls(RawMaterial.rgl(os.fspath(path)), threads)

    @property
    def name(self) -> str:
        """The model: ``"conductor"``, ``"dielectric"``, ``"rgl"``, ..."""
        return self._raw.name

    @property
    def spec(self) -> str:
        """The spec that ``from_spec`` turns back into this material."""
        return self._raw.spec

    @property
    def transmissive(self) -> bool:
        return self._raw.transmissive

    @property
    def isotropic(self) -> bool:
        return self._raw.isotropic

    def __repr__(self) -> str:
        return f"diffbsdf.Material({self.spec!r})"

    def eval(self, wi: object, wo: object, threads: Optional[int] = None) -> np.ndarray:
        """``f(wi, wo) * |cos theta_o|`` per RGB channel, ``(N, 3)`` float32."""
        return self._raw.eval(as_rows(wi, 3, "wi"), as_rows(wo, 3, "wo"), self._threads(threads))

    def eval_luminance(self, wi: object, wo: object, threads: Optional[int] = None) -> np.ndarray:
        """Luminance of ``f(wi, wo) * |cos theta_o|``, ``(N,)`` float32."""
        return self._raw.eval_luminance(
            as_rows(wi, 3, "wi"), as_rows(wo, 3, "wo"), self._threads(threads)
        )

    def sample(
        self, wi: object, u: object, threads: Optional[int] = None
    ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The material's own sampler: ``(wo (N,3) float32, pdf (N,) float32, valid (N,) bool)``.

        ``u`` is ``(N, 3)`` in [0, 1]: two numbers for the direction, the third picks a lobe
        (unused by single-lobe materials). Invalid rows (lost mass) are 0.
        """
        return self._raw.sample(as_rows(wi, 3, "wi"), as_rows(u, 3, "u"), self._threads(threads))

    def pdf(self, wi: object, wo: object, threads: Optional[int] = None) -> np.ndarray:
        """Density of the material's sampler at ``wo``, per unit solid angle, ``(N,)`` float32."""
        return self._raw.pdf(as_rows(wi, 3, "wi"), as_rows(wo, 3, "wo"), self._threads(threads))

    def _threads(self, threads: Optional[int]) -> Optional[int]:
        return _check_threads(self.threads if threads is None else threads)
