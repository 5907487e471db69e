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
# The declared minimum Rust version (one home: `rust-version` in Cargo.toml) is built, not assumed.
msrv=$(sed -n 's/^rust-version = "\(.*\)"/\1/p' Cargo.toml)
rustup toolchain list | grep -q "^${msrv}-" || rustup toolchain install "$msrv" --profile minimal

# The tests run natively (AVX2 where the machine has it); floats are the same either way
# (no contraction), only speed differs. The C library's portability is checked below.
export RUSTFLAGS="${RUSTFLAGS:--C target-cpu=native}"

# Each section prints the seconds since the start, so a log shows where the time goes.
section() { echo "== $1 (${SECONDS} s)"; }

section "format";  cargo fmt --all -- --check
section "clippy";  cargo clippy --workspace --all-targets -- -D warnings
section "no_std kernel on bare metal"; env -u RUSTFLAGS cargo build -p diffbsdf --target thumbv7em-none-eabihf
section "kernel and C ABI on Rust $msrv"; CARGO_TARGET_DIR=target/msrv cargo +"$msrv" build -p diffbsdf -p diffbsdf-ffi
section "C library on baseline x86-64 (no AVX assumed), running the C example"
env -u RUSTFLAGS CARGO_TARGET_DIR=target/baseline cargo build --release -p diffbsdf-ffi
gcc -std=c99 -Wall -Wextra -pedantic -Werror -I ffi/include ffi/examples/sample.c \
  target/baseline/release/libdiffbsdf_ffi.a -lm -lpthread -ldl -o target/baseline/sample
target/baseline/sample models/conductor-ggx-a0.3-cu-disk.dbsdf > /dev/null
# The project's own object files use no 256-bit (AVX) registers outside the AVX2 copy of
# the kernel that the library selects at run time (`each_avx2`, only where the CPU has
# AVX2); dependencies may choose such a path at run time too (memchr does).
objdump -d target/baseline/release/libdiffbsdf_ffi.a | awk '
  /^[^ ]+\.o:/ { member = $1 }
  /^[0-9a-f]+ <.*>:$/ { fn = $2 }
  /%ymm/ && member ~ /^diffbsdf/ && fn !~ /each_avx2/ { avx++ }
  /%ymm/ && fn ~ /each_avx2/ { selected++ }
  END {
    if (avx) { print "baseline C library: " avx " AVX instructions in diffbsdf code"; exit 1 }
    if (!selected) { print "baseline C library: no AVX2 copy of the kernel"; exit 1 }
  }'
# Its AVX2 copy gives the same bits as its baseline copy (built here for baseline x86-64).
env -u RUSTFLAGS CARGO_TARGET_DIR=target/baseline cargo test --release -p diffbsdf-ffi --test parallel --test slices
# So do the trainer's matrix products (its AVX2 copy against the one built for baseline).
env -u RUSTFLAGS CARGO_TARGET_DIR=target/baseline cargo test --release -p diffbsdf-train --lib tiles
section "docs";    RUSTDOCFLAGS="-D warnings" cargo doc --no-deps -p diffbsdf -p diffbsdf-ffi -p diffbsdf-codegen
section "tests";   cargo test --release --workspace
# The kernel's input-facing tests once more without --release: debug assertions and
# overflow checks on (profile.test, opt-level 1). The targets that exercise parsing and
# edge inputs (the blob fuzzer with 2 000 inputs, robustness, hard cases, base
# distributions, the model definition, the declared incident range); the long numerical
# suites (normalization 11 min unoptimised, shipped_models, pdf_consistency, isotropy,
# bijectivity, blob) run in release above. About 80 s measured on 2 busy cores.
# The kernel with fused multiply-add (the `fma` feature; RUSTFLAGS above target this CPU):
# every shipped model stays exact, and the property and hard-case suites hold; the
# generated C made to fuse the same multiply-adds agrees with it. A CPU without FMA cannot
# run it, and says so.
section "kernel with the fma feature"
grep -qw fma /proc/cpuinfo || { echo "this CPU has no FMA: the fma feature cannot be tested here"; exit 1; }
cargo test --release -p diffbsdf --features fma --lib --test shipped_models --test pdf_consistency \
  --test bijectivity --test jacobian --test hard_cases --test robustness --test batch
# and the generated C with its multiply-adds fused (`fused`, `--fma`) against that kernel
cargo test --release -p diffbsdf-codegen --features diffbsdf/fma --test c_header

section "kernel tests in debug (overflow checks)"
DIFFBSDF_FUZZ_INPUTS=2000 cargo test -p diffbsdf --lib \
  --test base_distributions --test fuzz_blob --test hard_cases --test incident_range \
  --test jacobian --test model_def --test robustness

section "python package (numpy API, Mitsuba 3 plugin)"
# A venv under target/ (gitignored); pip and maturin skip what is already there.
# Mitsuba's LLVM variants load libLLVM at run time: Debian's libllvm19.
llvm_so=/usr/lib/x86_64-linux-gnu/libLLVM-19.so
[ -e "$llvm_so" ] || [ -e "$llvm_so.1" ] || {
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq libllvm19
}
[ -e "$llvm_so" ] || llvm_so="$llvm_so.1"
pyvenv=target/pyvenv
[ -x "$pyvenv/bin/python" ] || python3 -m venv "$pyvenv"
"$pyvenv/bin/python" -m pip install -q --disable-pip-version-check \
  "maturin>=1.5,<2" "numpy>=1.24" "mitsuba==3.9.1" "pytest>=7"
VIRTUAL_ENV="$PWD/$pyvenv" "$pyvenv/bin/maturin" develop --release -q -m python/Cargo.toml
DRJIT_LIBLLVM_PATH="$llvm_so" "$pyvenv/bin/python" -m pytest -q python/tests
section "done"
