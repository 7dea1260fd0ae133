#!/usr/bin/env bash
# Peak memory of a run over ranks: the 1 000 000-particle bed (cases/box_hm_1m.toml, a few
# steps) in one process and on RANKS ranks (oversubscribed, 1 thread each), each process's
# maximum resident set from /usr/bin/time. Prints each rank's peak and the sum over the ranks
# per particle, and puts the table on top of bench/results/<date>-ranks-memory.md. Needs the
# data files of compare-peers.sh (it writes the 1 M bed if missing), OpenMPI and a build with
# --features mpi (made here).
#
#   bench/ranks-memory.sh            (RANKS="2 4" STEPS=10 by default)
set -euo pipefail
{
cd "$(dirname "$0")/.."
ROOT=$PWD
RANKS=${RANKS:-2 4}
STEPS=${STEPS:-10}
DATA=$ROOT/bench/cases/data
[ -f "$DATA/box_hm_settled.data" ] || { echo "missing $DATA/box_hm_settled.data: run bench/compare-peers.sh first" >&2; exit 2; }
[ -f "$DATA/box_hm_1m.data" ] || python3 bench/make-large-bed.py "$DATA/box_hm_settled.data" 10 "$DATA/box_hm_1m.data" 0
command -v mpirun >/dev/null || { echo "mpirun is missing: apt-get install -y libopenmpi-dev openmpi-bin" >&2; exit 2; }
cargo build --release --quiet -p grainflow-cli --features mpi
GF=$ROOT/target/release/grainflow
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
dt=$(awk '/^dt = /{print $3}' "$ROOT/bench/cases/box_hm_1m.toml")
sed "s|file = \"data/|file = \"$DATA/|; s|^t_stop = .*|t_stop = $(python3 -c "print($STEPS*$dt)")|" \
  "$ROOT/bench/cases/box_hm_1m.toml" > "$W/case.toml"
cat > "$W/wrap.sh" <<EOF
#!/bin/bash
exec /usr/bin/time -f "%M" -o "$W/rss.\$OMPI_COMM_WORLD_RANK" "\$@"
EOF
chmod +x "$W/wrap.sh"
N=1000000
row() { # label, KB per process...
  local label=$1; shift
  python3 - "$label" "$N" "$@" <<'PY'
import sys
label, n, kb = sys.argv[1], int(sys.argv[2]), [int(k) for k in sys.argv[3:]]
each = " / ".join(f"{k / 1024:.0f}" for k in kb)
print(f"| {label} | {each} | {sum(kb) * 1024 / n:.0f} |")
PY
}
{
  echo "## $(date -u +%FT%H:%MZ), git $(git -C "$ROOT" rev-parse --short HEAD), $STEPS steps of box_hm_1m ($N particles)"
  echo
  echo "| run | peak resident set per process, MiB (rank 0 first) | sum ÷ particles, B |"
  echo "|---|---|---|"
  /usr/bin/time -f "%M" -o "$W/one" "$GF" run "$W/case.toml" --out "$W/one-out" -q -j 1 > /dev/null
  row "one process" "$(cat "$W/one")"
  for r in $RANKS; do
    rm -f "$W"/rss.*
    mpirun --allow-run-as-root --oversubscribe -np "$r" "$W/wrap.sh" "$GF" run "$W/case.toml" \
      --out "$W/r$r-out" -q -j 1 > /dev/null
    row "$r ranks" $(for k in $(seq 0 $((r - 1))); do cat "$W/rss.$k"; done)
  done
  echo
} > "$W/table.md"
cat "$W/table.md"
OUT=$ROOT/bench/results/$(date -u +%F)-ranks-memory.md
{ cat "$W/table.md"; [ -f "$OUT" ] && cat "$OUT"; } > "$W/all.md"
mv "$W/all.md" "$OUT"
exit
}
