#!/usr/bin/env bash
# Packs what a GPU machine without a Rust toolchain needs to run the GPU figures
# (scripts/device_run.sh): a stripped release `experiment`, the models that figure6, figure8
# and the 2010 GPU specs (ao2010_figure3, _figure4, _models, _sponza) read, the commit they
# were built from, and the Vulkan loader packages. Run it here, then on
# the GPU machine (the device tool; both folders are git-ignored and named in `carry`):
#   run(command="bash scripts/device_run.sh", carry=[".device", ".gl"], timeout_s=600)
# Commit first: the packed build records HEAD, and a dirty tree is refused.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -n "$(git status --porcelain --untracked-files=no -- . ':!results')" ]; then
  echo "device_pack: commit your changes first (the packed build names HEAD)" >&2
  exit 1
fi
cargo build --release --bin experiment
rm -rf .device
mkdir -p .device/models
strip -o .device/experiment target/release/experiment
git rev-parse HEAD >.device/COMMIT
# The models of figure6, figure8 and the 2010 GPU specs, from where the project finds models.
models_dir=""
for d in "${VISFIELD_MODELS:-}" data/models ../shared/models; do
  if [ -n "$d" ] && [ -f "$d/stanford-bunny_39k.obj" ]; then models_dir="$d"; break; fi
done
if [ -z "$models_dir" ]; then
  echo "device_pack: stanford-bunny_39k.obj not found in \$VISFIELD_MODELS, data/models or ../shared/models" >&2
  exit 1
fi
for f in stanford-bunny_39k.obj igea_67k.obj Tree_3.obj Tree_3.mtl elephant.obj dragon.obj \
  cow.obj sponza.obj; do
  cp "$models_dir/$f" .device/models/
done
# The Vulkan loader (the GPU machine has the NVIDIA driver but may lack libvulkan).
if [ ! -d .gl ] || ! ls .gl/libvulkan1_*.deb >/dev/null 2>&1; then
  mkdir -p .gl /tmp/amd64/partial
  o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64'
  # shellcheck disable=SC2086
  apt-get $o update >/dev/null
  # shellcheck disable=SC2086
  (cd .gl && apt-get $o download libvulkan1)
fi
du -sh .device .gl
echo "device_pack: packed $(cat .device/COMMIT)"
