#!/usr/bin/env bash
# One spec's cells on a SLURM cluster: a job array of N shards, each running
# `experiment NAME --shard I/N` into its own folder, all sharing one field cache on a shared
# filesystem (writes are atomic and content-addressed, so concurrent shards baking the same
# field are safe). Join the shards afterwards with `experiment merge` (printed below).
#
#   sbatch --array=1-8 scripts/slurm_shards.sh figure6           # 8 shards of figure6
#   sbatch --array=1-8 scripts/slurm_shards.sh figure6 --quick   # the same, quick profile
#
# Environment: VISFIELD_SHARDS_ROOT (default: $PWD/shards) holds the shards' folders and the
# cache; EXPERIMENT (default: target/release/experiment, built beforehand with
# `cargo build --release`, with `--features embree` for the specs that ask for Embree).
#SBATCH --job-name=visfield
#SBATCH --cpus-per-task=2
#SBATCH --time=04:00:00
set -euo pipefail

NAME="${1:?usage: sbatch --array=1-N scripts/slurm_shards.sh SPEC_NAME [experiment flags...]}"
shift
I="${SLURM_ARRAY_TASK_ID:?run as a job array: sbatch --array=1-N ...}"
N="${SLURM_ARRAY_TASK_COUNT:?run as a job array: sbatch --array=1-N ...}"
ROOT="${VISFIELD_SHARDS_ROOT:-$PWD/shards}"
EXPERIMENT="${EXPERIMENT:-target/release/experiment}"
mkdir -p "$ROOT/cache"

"$EXPERIMENT" "$NAME" "$@" --shard "$I/$N" --cache "$ROOT/cache" --out "$ROOT/$NAME-$I-of-$N"

if [ "$I" = "$N" ]; then
  echo "when every shard has finished:"
  echo "  $EXPERIMENT merge $ROOT/$NAME-merged $ROOT/$NAME-*-of-$N"
fi
