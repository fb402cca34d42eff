#!/usr/bin/env bash
# Bounded fuzzing of every uTile target (docs/RELIABILITY.md): `fuzz/run.sh [SECONDS] [TARGET...]`,
# default 60 s per target, all targets. Needs cargo-fuzz (`cargo install cargo-fuzz --locked`)
# and the pinned nightly. New inputs go to fuzz/work/<target>/ (not committed); the seed
# corpus fuzz/corpus/<target>/ is only read. A crash is saved under fuzz/artifacts/<target>/
# and the script stops with its path; add it to fuzz/corpus/<target>/ once fixed, so
# tests/fuzz_replay.rs keeps checking it.
set -euo pipefail
cd "$(dirname "$0")/.."
secs=${1:-60}
[ $# -gt 0 ] && shift
targets=("$@")
# Every target in fuzz/fuzz_targets/ unless some are named: a new target is fuzzed at once.
if [ ${#targets[@]} -eq 0 ]; then
    for f in fuzz/fuzz_targets/*.rs; do
        t=${f##*/}
        targets+=("${t%.rs}")
    done
fi
command -v cargo-fuzz >/dev/null 2>&1 || cargo install cargo-fuzz --locked
for t in "${targets[@]}"; do
    mkdir -p "fuzz/work/$t"
    printf '\033[1m==> fuzz %s for %s s\033[0m\n' "$t" "$secs" >&2
    cargo fuzz run -O "$t" "fuzz/work/$t" "fuzz/corpus/$t" -- \
        -max_total_time="$secs" -max_len=4096 -timeout=20 -print_final_stats=1 2>&1 |
        grep -E '^(#[0-9]+ +DONE|stat::number_of_executed_units|stat::new_units_added|==[0-9]+==|SUMMARY|.*panicked|.*invariant broken|artifact_prefix|Test unit written)' || true
    if ls "fuzz/artifacts/$t"/crash-* >/dev/null 2>&1; then
        echo "fuzz target $t found a crash: $(ls fuzz/artifacts/$t/crash-*)" >&2
        exit 1
    fi
done
