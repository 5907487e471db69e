import os
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
MODELS = ROOT / "models"

# Mitsuba's LLVM variants load libLLVM at run time; scripts/test.sh installs libllvm19.
os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so")


@pytest.fixture(scope="session")
def models() -> pathlib.Path:
    return MODELS
