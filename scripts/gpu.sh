#!/usr/bin/env bash
# On a machine with a GPU (Vulkan driver and loader installed, glslang-tools and
# spirv-tools on the PATH): runs the generated-code conformance tests on that GPU's driver
# instead of lavapipe, then times the generated WGSL there (docs/performance.md, "On a
# GPU"; docs/codegen.md, "What runs on the GPU"). Never part of the test command: nothing
# depends on a GPU.
#
#   scripts/gpu.sh [ADAPTER]     # ADAPTER: part of the adapter's name, default NVIDIA
set -euo pipefail
cd "$(dirname "$0")/.."
adapter="${1:-NVIDIA}"
DIFFBSDF_GPU_ADAPTER="$adapter" cargo test --release -p diffbsdf-codegen --test gpu -- \
  --nocapture --test-threads 1
cargo run --release -p diffbsdf-codegen --example gpu_timing -- --adapter "$adapter"
