#!/usr/bin/env bash
# Installs what the tests need (idempotent) and runs every test of the workspace.
# Used by `.ci/run`; a missing tool makes the run fail, never skip.
set -euo pipefail
cd "$(dirname "$0")/.."

need_apt=()
command -v glslangValidator >/dev/null 2>&1 || need_apt+=(glslang-tools)
command -v spirv-val >/dev/null 2>&1 || need_apt+=(spirv-tools)
[ -e /usr/share/vulkan/icd.d/lvp_icd.x86_64.json ] || [ -e /usr/share/vulkan/icd.d/lvp_icd.json ] || need_apt+=(mesa-vulkan-drivers)
ldconfig -p 2>/dev/null | grep -q 'libvulkan.so.1' || need_apt+=(libvulkan1)
command -v gcc >/dev/null 2>&1 || need_apt+=(gcc)
command -v g++ >/dev/null 2>&1 || need_apt+=(g++)
if [ ${#need_apt[@]} -gt 0 ]; then
  echo "installing: ${need_apt[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${need_apt[@]}"
fi
rustup target list --installed | grep -q thumbv7em-none-eabihf || rustup target add thumbv7em-none-eabihf
rustup component list --installed | grep -q rustfmt || rustup component add rustfmt
rustup component list --installed | grep -q clippy || rustup component add clippy

echo "== format";  cargo fmt --all -- --check
echo "== clippy";  cargo clippy --workspace --all-targets -- -D warnings
echo "== no_std kernel on bare metal"; cargo build -p diffbsdf --target thumbv7em-none-eabihf
echo "== tests";   cargo test --release --workspace
