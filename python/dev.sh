#!/usr/bin/env bash
# For working on the package: builds the native module (dev profile, the workspace's target
# folder) and puts it into python/specmap/, so that `PYTHONPATH=python python -c "import specmap"`
# runs this tree without a pip install. Several may run at once (flock; the copy is renamed in).
set -euo pipefail
cd "$(dirname "$0")/.."
exec 9>target/.python-dev.lock
flock 9
cargo build --quiet -p specmap-python
cp target/debug/lib_specmap.so python/specmap/.tmp_specmap.so
mv python/specmap/.tmp_specmap.so python/specmap/_specmap.abi3.so
