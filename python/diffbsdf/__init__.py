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

Threads: the GIL is released and a batch is split into contiguous chunks over
``threads`` OS threads (default: ``available_threads()``, i.e. the machine's available
parallelism; set ``Model.threads`` or pass ``threads=`` per call). Every row is
computed independently, so the result does not depend on the thread count.
"""

from __future__ import annotations

import os
from typing import Optional, Tuple, Union

import numpy as np

from ._diffbsdf import KERNEL_VERSION, BlobFormatError, RawModel, available_threads

__all__ = ["Model", "BlobFormatError", "available_threads", "KERNEL_VERSION", "as_rows"]
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
        """``"disk"`` (BRDF, ``wi.z >= 0`` only, samples the upper hemisphere) or ``"sphere"``."""
        return self._raw.domain

    @property
    def default_steps(self) -> int:
        """Euler steps used when ``steps=None``."""
        return self._raw.default_steps

    @property
    def isotropic(self) -> bool:
        return self._raw.isotropic

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
