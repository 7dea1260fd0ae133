#!/usr/bin/env bash
# What stepping from Python costs over `grainflow run` (issue 41): box_hm (10 000 Hertz
# spheres settled in a box, the state compare-peers.sh writes into cases/data), 5 000 steps on
# one thread, alternated rounds: the program's own timed loop against a Python script that
# steps the same case in chunks of 100 steps (`sim.step(100)`, reading a view between chunks).
# Speeds are particle-steps per second: the program's as it prints them, the script's over
# its stepping alone (set-up excluded, as the program's is).
#
#   bench/python-overhead.sh    (RUNS=5; PYTHON=a python with grainflow installed, else a venv
#                                in target/py-venv gets it; CARGO="flock LOCK cargo")
set -euo pipefail
{
cd "$(dirname "$0")/.."
ROOT=$PWD
RUNS=${RUNS:-5}
CARGO=${CARGO:-cargo}
$CARGO build --release --quiet -p grainflow-cli
GF=$ROOT/target/release/grainflow
if [ -z "${PYTHON:-}" ]; then
  if [ ! -x target/py-venv/bin/python ] || ! target/py-venv/bin/python -c "import maturin, numpy" 2>/dev/null; then
    python3 -m venv target/py-venv
    target/py-venv/bin/pip install --quiet maturin numpy pytest
  fi
  # maturin takes $CARGO for the cargo program: the build lock's wrapper is not one.
  env -u CARGO PATH="$ROOT/target/py-venv/bin:$PATH" target/py-venv/bin/pip install --quiet --no-build-isolation --force-reinstall --no-deps ./python
  PYTHON=$ROOT/target/py-venv/bin/python
fi
[ -f bench/cases/data/box_hm_settled.data ] || { echo "needs bench/cases/data/box_hm_settled.data (bench/compare-peers.sh writes it)" >&2; exit 2; }
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
CASE=$ROOT/bench/cases/box_hm.toml
cat > "$W/step.py" <<'PY'
import sys, time
import grainflow
sim = grainflow.Simulation.from_case(sys.argv[1], threads=1, overrides={"time.t_stop": 0.1})
n = len(sim.particles)
t0 = time.perf_counter()
while sim.step_count < sim.total_steps:
    sim.step(100)
    _ = sim.particles.position[0, 2]
wall = time.perf_counter() - t0
print(f"{n * sim.step_count / wall / 1e6:.3f}")
PY
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
speed() { awk '/particle-steps\/s on/{for(k=1;k<=NF;k++) if($k=="particle-steps/s") print $(k-1)/1e6}' "$1"; }
: > "$W/cli"; : > "$W/py"
for r in $(seq "$RUNS"); do
  rm -rf "$W/out"
  "$GF" run "$CASE" --set time.t_stop=0.1 -j 1 --out "$W/out" -q > "$W/log"
  speed "$W/log" >> "$W/cli"
  "$PYTHON" "$W/step.py" "$CASE" >> "$W/py"
  echo "round $r: grainflow run $(tail -1 "$W/cli"), Python $(tail -1 "$W/py")" >&2
done
CLI=$(median < "$W/cli"); PY=$(median < "$W/py")
OUT=$ROOT/bench/results/$(date -u +%F)-python-overhead.md
{
  echo "# Stepping from Python against grainflow run ($(date -u +%FT%RZ), git $(git rev-parse --short HEAD))"
  echo
  echo "box_hm, 5 000 steps on one thread, $RUNS alternated rounds; millions of particle-steps/s."
  echo
  echo "| round | grainflow run | Python, chunks of 100 | Python ÷ run |"
  echo "|---|---|---|---|"
  paste -d' ' "$W/cli" "$W/py" | awk '{printf "| %d | %.3f | %.3f | %.3f |\n", NR, $1, $2, $2 / $1}'
  echo
  echo "Medians: grainflow run $CLI, Python $PY, Python ÷ run $(python3 -c "print(f'{$PY / $CLI:.3f}')");" \
    "median of the rounds' ratios $(paste -d' ' "$W/cli" "$W/py" | awk '{print $2 / $1}' | median | xargs printf '%.3f')."
  echo
  [ -f "$OUT" ] && cat "$OUT"
} > "$W/table"
mv "$W/table" "$OUT"
cat "$OUT"
}
