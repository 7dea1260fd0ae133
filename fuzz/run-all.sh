#!/usr/bin/env bash
# Runs every fuzz target for SECONDS (default 600) each, one after the other, from the
# repository root; prints each target's execution count and whether it found a crash.
set -uo pipefail
cd "$(dirname "$0")/.."
secs="${SECONDS_PER_TARGET:-600}"
for t in case_file mfix_particles csv_particles lammps_data mfix_deck mfix_expr liggghts_script checkpoint; do
  log="fuzz/last-run-$t.log"
  RUSTC_BOOTSTRAP=1 cargo fuzz run -O "$t" "fuzz/corpus/$t" -- -max_total_time="$secs" -rss_limit_mb=4096 -timeout=10 >"$log" 2>&1
  rc=$?
  execs=$(grep -oE '^#[0-9]+' "$log" | tail -n 1 | tr -d '#')
  echo "$t: exit $rc, ${execs:-0} executions in ${secs} s$( [ -d "fuzz/artifacts/$t" ] && [ -n "$(ls -A "fuzz/artifacts/$t")" ] && echo ', CRASH: see fuzz/artifacts/'"$t" )"
done
