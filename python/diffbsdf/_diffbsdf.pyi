from typing import Optional, Tuple

import numpy as np
import numpy.typing as npt

KERNEL_VERSION: str
MAX_STEPS: int

class BlobFormatError(ValueError): ...

def available_threads() -> int: ...

class RawModel:
    @staticmethod
    def from_bytes(blob: bytes) -> RawModel: ...
    @property
    def domain(self) -> str: ...
    @property
    def default_steps(self) -> int: ...
    @property
    def isotropic(self) -> bool: ...
    @property
    def incident_range(self) -> str: ...
    @property
    def precision(self) -> str: ...
    @property
    def name(self) -> str: ...
    @property
    def shape(self) -> Tuple[Tuple[int, int, int], Tuple[int, int, int]]: ...
    def sample(
        self,
        wi: npt.NDArray[np.float32],
        u: npt.NDArray[np.float32],
        steps: Optional[int] = None,
        threads: Optional[int] = None,
    ) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.float32], npt.NDArray[np.bool_]]: ...
    def sample_direction(
        self,
        wi: npt.NDArray[np.float32],
        u: npt.NDArray[np.float32],
        steps: Optional[int] = None,
        threads: Optional[int] = None,
    ) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.bool_]]: ...
    def pdf(
        self,
        wi: npt.NDArray[np.float32],
        wo: npt.NDArray[np.float32],
        steps: Optional[int] = None,
        threads: Optional[int] = None,
    ) -> npt.NDArray[np.float32]: ...

class RawMaterial:
    @staticmethod
    def from_spec(spec: str) -> RawMaterial: ...
    @staticmethod
    def rgl(path: str) -> RawMaterial: ...
    @property
    def name(self) -> str: ...
    @property
    def spec(self) -> str: ...
    @property
    def transmissive(self) -> bool: ...
    @property
    def isotropic(self) -> bool: ...
    def eval(
        self,
        wi: npt.NDArray[np.float32],
        wo: npt.NDArray[np.float32],
        threads: Optional[int] = None,
    ) -> npt.NDArray[np.float32]: ...
    def eval_luminance(
        self,
        wi: npt.NDArray[np.float32],
        wo: npt.NDArray[np.float32],
        threads: Optional[int] = None,
    ) -> npt.NDArray[np.float32]: ...
    def sample(
        self,
        wi: npt.NDArray[np.float32],
        u: npt.NDArray[np.float32],
        threads: Optional[int] = None,
    ) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.float32], npt.NDArray[np.bool_]]: ...
    def pdf(
        self,
        wi: npt.NDArray[np.float32],
        wo: npt.NDArray[np.float32],
        threads: Optional[int] = None,
    ) -> npt.NDArray[np.float32]: ...
