#!/usr/bin/env bash
# Runs the GPU figures on a GPU machine from the build packed by scripts/device_pack.sh: figure6,
# figure8 and relief on the hardware adapter (a run fails rather than fall back to lavapipe),
# then the results as one archive in $OUT (the device tool returns at most 8 files).
# Budget: about 5 minutes on a 16-core machine with an H200; the time limit of the call should
# leave room for one rerun.
set -uo pipefail
cd "$(dirname "$0")/.."
out="${OUT:-/tmp/device-out}"
mkdir -p "$out"
# DEVICE_ADAPTER and DEVICE_ARGS (e.g. lavapipe and --quick) try the script on another machine;
# DEVICE_SKIP_LOADER=1 leaves its Vulkan loader alone. DEVICE_JOBS replaces the jobs (one per
# line or ";"-separated, each a spec name and its flags), e.g. the 2010 GPU specs:
#   DEVICE_JOBS="ao2010_figure3; ao2010_figure4; ao2010_models; ao2010_sponza"
# (their CPU side, the converged references and the 16642 × 128² bake, takes minutes even on
# 16 cores: run them in a call of their own). DEVICE_SET=moving runs the moving scenes with
# every GPU per-frame method instead (a call of its own): the 64-caster crowd per pixel
# (dynamic2010_crowd_gpu) and per vertex (dynamic2008_crowd_gpu), the animated 2008 Figure 8 (dynamic2008_figure8) and the 256-caster
# crowd (dynamic2010_crowd256_gpu): two_level@gpu, rayquery@gpu (where offered), field_every_sphere@gpu and field@gpu beside
# their CPU twins (and world_rebuild@gpu where the world fits one storage binding), each
# frame's update and query timed apart. The crowds share their fields through cache/ (one bake
# of the five meshes); add DEVICE_ARGS=--quick for a first, short try.
adapter="${DEVICE_ADAPTER:-hardware}"
if [ -z "${DEVICE_SKIP_LOADER:-}" ]; then
  for f in .gl/*.deb; do dpkg -x "$f" /; done
  ldconfig
fi
if [ ! -e /usr/share/vulkan/icd.d/nvidia_icd.json ] && [ -e /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ]; then
  export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
fi
export VISFIELD_MODELS="$PWD/.device/models" VISFIELD_COMMIT="$(cat .device/COMMIT)"
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | tee "$out/gpu.txt" || true
exp=.device/experiment
status=0
case "${DEVICE_SET:-figures}" in
  moving) default_jobs="dynamic2010_crowd_gpu; dynamic2008_crowd_gpu; dynamic2008_figure8 --no-cache; dynamic2010_crowd256_gpu" ;;
  *) default_jobs="figure6 --no-cache; figure8 --no-cache; relief" ;;
esac
jobs="${DEVICE_JOBS:-$default_jobs}"
IFS=$';\n' read -r -d '' -a job_list <<<"$jobs" || true
for job in "${job_list[@]}"; do
  job="$(echo "$job" | xargs)"
  [ -z "$job" ] && continue
  name="${job%% *}"
  echo "== $name"
  # shellcheck disable=SC2086
  if ! $exp $job --adapter "$adapter" ${DEVICE_ARGS:-} --out "results-device/$name" 2>&1 | tee "$out/$name.log"; then
    status=1
  fi
done
# The adapter each run used, as its run.json records it (the GPU rows name it too).
grep -ho '"gpu_adapter": *"[^"]*"\|"adapter": *"[^"]*"' results-device/*/run.json 2>/dev/null \
  | sort -u | tee "$out/adapter.txt" || true
# Whether the adapter offered ray queries: a run that asked for them and was refused lists
# rayquery@gpu (or rayquery) in run.json's skipped_methods with the reason.
if grep -l '"method": *"rayquery' results-device/*/run.json 2>/dev/null | xargs -r grep -l 'no ray queries' >/dev/null 2>&1; then
  echo "ray queries: not offered (runs skipped them; see run.json skipped_methods)" | tee "$out/ray_queries.txt"
else
  echo "ray queries: offered, or no run asked for them" | tee "$out/ray_queries.txt"
fi
tar czf "$out/results-device.tgz" results-device
exit $status
