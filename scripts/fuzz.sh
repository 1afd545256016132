#!/usr/bin/env bash
# Fuzzes the spec parser, mesh validation, the OBJ and PLY loaders and PLY headers built from
# the input (counts, repeated elements, elements without properties) for a bounded time per
# target (default 60 s):
#   scripts/fuzz.sh [SECONDS] [TARGET...]
# Needs cargo-fuzz (`cargo install cargo-fuzz`). On a stable toolchain, RUSTC_BOOTSTRAP=1 lets
# cargo-fuzz use the sanitizer flags it needs. A crash is saved under fuzz/artifacts/TARGET/;
# turn it into a regression test (tests/fuzz_regressions.rs) before fixing it.
# Not part of CI (.ci/run): run it by hand, niced.
set -euo pipefail
cd "$(dirname "$0")/../fuzz"
secs="${1:-60}"
shift || true
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then targets=(spec mesh_parts obj ply ply_header); fi
export RUSTC_BOOTSTRAP=1
status=0
for t in "${targets[@]}"; do
  echo "== fuzz $t for ${secs} s"
  mkdir -p "corpus/$t"
  if ! nice -n 10 cargo fuzz run "$t" "corpus/$t" -- -max_total_time="$secs" -rss_limit_mb=2048 \
      -timeout=10; then
    echo "fuzz $t: crash found (see fuzz/artifacts/$t/)"
    status=1
  fi
done
exit $status
