#!/usr/bin/env bash
# The whole test suite, from a fresh clone: installs what the tests need, then runs
# formatting and lint checks, the Rust unit and integration tests, and the Python interop tests
# that compare specmap with independent references (colour-science, tmm, OpenEXR).
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TERM_COLOR="${CARGO_TERM_COLOR:-never}"
# Incremental caches only pay off across edits; on a fresh clone they are 1.5 GB of disk.
if [ -n "${CI:-}" ]; then export CARGO_INCREMENTAL=0; fi

# Each step says when it starts (seconds into the suite), so a slow step shows in CI's log.
step() { printf '\n== %s (at %d s)\n' "$*" "$SECONDS"; }

step "Disk"
# On a clean clone the suite leaves target/ at 1.8 GB and the venv at 0.6 GB (`du -sm target
# .venv` after `bash .ci/run`); say up front when the disk has less than that, with a margin,
# rather than fail half-way with "No space left on device".
NEED_MB=3000
free_mb=$(df -Pm . | awk 'NR==2 {print $4}')
echo "free: ${free_mb} MB in $(pwd) (the suite needs about ${NEED_MB} MB)"
if [ "${free_mb:-0}" -lt "$NEED_MB" ]; then
  echo "warning: less free disk than the suite needs; it may stop with 'No space left on device'" >&2
fi

step "Software Vulkan adapter for the GPU renderer tests (Mesa lavapipe)"
# The renderer's GPU/CPU agreement test runs on any Vulkan adapter; lavapipe is a CPU one, so
# the test runs on machines without a GPU too. Needs root (CI runs as root) or the packages present.
if ! dpkg -s mesa-vulkan-drivers libvulkan1 >/dev/null 2>&1; then
  if [ "$(id -u)" = 0 ]; then
    export DEBIAN_FRONTEND=noninteractive
    apt-get install -y -qq mesa-vulkan-drivers libvulkan1 >/dev/null 2>&1 \
      || { apt-get update -qq && apt-get install -y -qq mesa-vulkan-drivers libvulkan1 >/dev/null; }
  else
    echo "mesa-vulkan-drivers/libvulkan1 missing and not root: install them to run the GPU tests" >&2
    exit 1
  fi
fi
# Installs Debian package $2 unless command $1 is on the PATH (root; else says so and stops).
need_command() {
  if command -v "$1" >/dev/null 2>&1; then return; fi
  if [ "$(id -u)" = 0 ]; then
    export DEBIAN_FRONTEND=noninteractive
    apt-get install -y -qq "$2" >/dev/null 2>&1 \
      || { apt-get update -qq && apt-get install -y -qq "$2" >/dev/null; }
  else
    echo "$1 missing and not root: install the Debian package $2" >&2
    exit 1
  fi
}
step "GNU parallel for the batch shard test (Debian package parallel)"
# tests/batch.rs runs two shards of one batch at once under GNU parallel, as the README's recipe.
need_command parallel parallel
step "Xvfb for the view's window tests (Debian package xvfb)"
# tests/view.rs opens \`specmap view\` in a real window on a private Xvfb display (lavapipe
# draws it); a missing Xvfb fails the suite, as a missing GPU adapter does.
need_command Xvfb xvfb
step "LLVM for Mitsuba's llvm_ad_spectral variant (Debian package libllvm19)"
# tests/interop/test_mitsuba.py runs the specmap_envmap emitter in llvm_ad_spectral too; Dr.Jit
# crashes with the stock LLVM 15, so it is pointed at LLVM 19 (the test skips without one).
if ! dpkg -s libllvm19 >/dev/null 2>&1; then
  if [ "$(id -u)" = 0 ]; then
    export DEBIAN_FRONTEND=noninteractive
    apt-get install -y -qq libllvm19 >/dev/null 2>&1 \
      || { apt-get update -qq && apt-get install -y -qq libllvm19 >/dev/null; }
  else
    echo "libllvm19 missing and not root: test_mitsuba.py's llvm_ad_spectral cases will skip" >&2
  fi
fi
if [ -z "${DRJIT_LIBLLVM_PATH:-}" ]; then
  for lib in /usr/lib/x86_64-linux-gnu/libLLVM.so.19* /usr/lib/*/libLLVM-19.so /usr/lib/llvm-19/lib/libLLVM.so*; do
    if [ -e "$lib" ]; then export DRJIT_LIBLLVM_PATH="$lib"; break; fi
  done
fi
echo "DRJIT_LIBLLVM_PATH=${DRJIT_LIBLLVM_PATH:-unset}"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp/specmap-xdg-$(id -u)}"
mkdir -p "$XDG_RUNTIME_DIR" && chmod 700 "$XDG_RUNTIME_DIR"
# The GPU tests must run here, not skip: a missing adapter is a failure in this suite.
export SPECMAP_REQUIRE_GPU=1
# The suite's fits are stored in a cache of its own, made fresh each run: never in the user's,
# and never one a run before it filled.
export SPECMAP_CACHE_DIR="$(mktemp -d "${TMPDIR:-/tmp}/specmap-test-cache.XXXXXX")"
trap 'rm -rf "$SPECMAP_CACHE_DIR"' EXIT

step "Python venv for the interop tests (.venv)"
if ! .venv/bin/python -c "import colour, tmm, OpenEXR, pytest, scipy, mitsuba" 2>/dev/null \
   || ! cmp -s tests/interop/requirements.txt .venv/.requirements 2>/dev/null; then
  python3 -m venv .venv
  .venv/bin/pip install --quiet --disable-pip-version-check --no-cache-dir --upgrade pip
  .venv/bin/pip install --quiet --disable-pip-version-check --no-cache-dir -r tests/interop/requirements.txt
  cp tests/interop/requirements.txt .venv/.requirements
fi
.venv/bin/python -c "import colour; print('colour-science', colour.__version__)"

step "cargo fmt --check"
cargo fmt --all -- --check

step "no function over 80 lines without a reason, no import circle (tools/)"
python3 tools/long_functions.py --check src
python3 tools/import_circles.py --check

step "cargo clippy --workspace --all-targets -D warnings (the crate and python/)"
cargo clippy --workspace --all-targets --quiet -- -D warnings

step "cargo test (unit + integration)"
cargo test --all-targets --quiet 2>&1 | tee target/cargo-test.log
# Doc tests too (examples in the docs must compile and pass).
cargo test --doc --quiet

step "numbered examples (examples/0*.rs: built, and each run once)"
# cargo test built them already; this puts each at target/debug/examples/NAME.
cargo build --quiet --examples
for example in examples/0*.rs; do
  name=$(basename "$example" .rs)
  echo "-- $name"
  "target/debug/examples/$name" >/dev/null
done

step "interop tests (pytest)"
# test_exrio.py runs the write_spectral example: built here (cargo test built it already, so
# this is a check), and named so that each case starts the binary, not cargo.
cargo build --quiet --example write_spectral
export SPECMAP_WRITE_SPECTRAL="$PWD/target/debug/examples/write_spectral"
# The slowest cases are listed at the end, to keep the suite's time in view.
SPECMAP_BIN="$PWD/target/debug/specmap" .venv/bin/python -m pytest tests/interop -q \
  -p no:cacheprovider --durations=12

step "the Python package (python/: built by maturin into .venv, then its pytest suite)"
# Built as a user's `pip install ./python` builds it, but in the dev profile: it shares the
# crate and the dependencies cargo test compiled above (target/debug), so it only compiles the
# bindings. --no-build-isolation uses the maturin pinned in tests/interop/requirements.txt.
PATH="$PWD/.venv/bin:$PATH" MATURIN_PEP517_ARGS="--profile dev" \
  .venv/bin/pip install --quiet --disable-pip-version-check --no-build-isolation --no-deps \
  --force-reinstall ./python
SPECMAP_BIN="$PWD/target/debug/specmap" .venv/bin/python -m pytest python/tests -q \
  -p no:cacheprovider --durations=8
echo "the suite took ${SECONDS} s"
