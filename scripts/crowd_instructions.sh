#!/usr/bin/env bash
# Instructions per ray of the moving crowd's query, the field against Embree's instances, from 1
# to 256 casters: one frame of `examples/crowd_cost.rs` (the quick crowd's supershapes, 64 AO rays
# a receiver vertex, u8 fields of 290 × 16²) on one thread under callgrind, counting the
# inclusive instructions of the method's `Visibility::occluded_many` (the whole query: the
# traversal of the top level, every per-instance call and lookup) divided by the frame's rays,
# (8·√N + 1)² · 64. Instruction counts do not depend on the machine's load. Writes
# results/crowd_instructions/table.csv and run.json (commit, valgrind, CPU, date).
#
# usage: scripts/crowd_instructions.sh [N ...]     (default 1 4 16 64 256; needs valgrind and
#        the system's Embree 3: apt-get install valgrind libembree-dev)
#        With CROWD_PROFILES=DIR CROWD_COMMIT=SHA, tabulates the profiles DIR/cg-METHOD-N.out
#        that this script's valgrind command made from a build of commit SHA, instead of
#        building and profiling again.
set -euo pipefail
cd "$(dirname "$0")/.."
counts=("$@")
[ ${#counts[@]} -eq 0 ] && counts=(1 4 16 64 256)
for n in "${counts[@]}"; do
  side=$(python3 -c "import math,sys; s=math.isqrt($n); sys.exit(0 if s*s==$n else 1); " && python3 -c "import math; print(math.isqrt($n))") || {
    echo "N = $n is not a perfect square (the crowd is a square grid)" >&2; exit 2; }
done
command -v valgrind >/dev/null || { echo "needs valgrind (apt-get install valgrind)" >&2; exit 2; }
profiles="${CROWD_PROFILES:-}"
[ -z "$profiles" ] || [ -n "${CROWD_COMMIT:-}" ] || { echo "CROWD_PROFILES needs CROWD_COMMIT" >&2; exit 2; }
[ -n "$profiles" ] || cargo build --release --features embree --example crowd_cost
bin=target/release/examples/crowd_cost
out=results/crowd_instructions
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "casters,method,rays,instructions,instructions_per_ray,node_tests_per_ray,instance_calls_per_ray,reads_per_ray" > "$tmp/table.csv"
for method in field embree_instances; do
  for n in "${counts[@]}"; do
    side=$(python3 -c "import math; print(math.isqrt($n))")
    rays=$(( (8 * side + 1) * (8 * side + 1) * 64 ))
    if [ -n "$profiles" ]; then
      cg="$profiles/cg-$method-$n.out"
    else
      cg="$tmp/cg-$method-$n.out"
      echo "callgrind: $method at $n casters ($rays rays)" >&2
      RAYON_NUM_THREADS=1 valgrind --tool=callgrind --callgrind-out-file="$cg" "$bin" "$n" "$method" 1 >/dev/null 2>&1
    fi
    callgrind_annotate --threshold=100 --inclusive=yes "$cg" > "$tmp/annotated" 2>/dev/null
    # The inclusive instructions of the first (outermost) function matching $1, or 0.
    inclusive() { grep -E "$1" "$tmp/annotated" | head -1 | awk '{gsub(",","",$1); print $1+0}'; }
    inc=$(inclusive "as visfield::visibility::Visibility>::occluded_many ")
    [ -n "$inc" ] || { echo "no occluded_many in the profile of $method at $n" >&2; exit 1; }
    per() { python3 -c "print(round(${1:-0}/$rays, 1))"; }
    if [ "$method" = field ]; then
      # The field's parts: the top level's node tests, the per-instance batched calls, and
      # within them the reads of the stored distances (none with one caster: no top level).
      node=$(per "$(inclusive 'sphere_bvh::avx2::test_lanes|sphere_bvh::BoxFrom::test_lanes')")
      calls=$(per "$(inclusive 'FieldInstance::occluded_many')")
      reads=$(per "$(inclusive 'lookup::NearestRead as visfield::field::lookup::Reads>::of_block')")
    else
      node=""; calls=""; reads=""
    fi
    echo "$n,$method,$rays,$inc,$(per "$inc"),$node,$calls,$reads" >> "$tmp/table.csv"
  done
done
if [ -n "$profiles" ]; then
  commit="$CROWD_COMMIT"
else
  commit=$(git rev-parse HEAD)
  [ -z "$(git status --porcelain)" ] || commit="$commit-dirty"
fi
python3 - "$tmp/run.json" "$commit" "${counts[*]}" <<'PY'
import json, platform, subprocess, sys, datetime
cpu = next((l.split(':', 1)[1].strip() for l in open('/proc/cpuinfo') if l.startswith('model name')), platform.machine())
json.dump({
    "command": "scripts/crowd_instructions.sh " + sys.argv[3],
    "commit": sys.argv[2],
    "valgrind": subprocess.run(["valgrind", "--version"], capture_output=True, text=True).stdout.strip(),
    "cpu": cpu,
    "threads": 1,
    "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
    "what": "instructions per ray of one frame's query (Visibility::occluded_many, inclusive) under callgrind, examples/crowd_cost.rs N METHOD 1",
}, open(sys.argv[1], "w"), indent=1)
PY
mkdir -p "$out"
cp "$tmp/table.csv" "$tmp/run.json" "$out/"
cat "$out/table.csv"
