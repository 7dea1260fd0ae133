#!/usr/bin/env bash
# What stepping from Python costs over `grainflow run` (issue 41): box_hm (10 000 Hertz
# spheres settled in a box, the state compare-peers.sh writes into cases/data), 5 000 steps on
# one thread, alternated rounds (each round in a rotated order): the program's own timed loop
# against a Python script that steps the same case in chunks of 100 steps (`sim.step(100)`,
# reading a view between chunks) and in one call (`sim.step(5000)`: the same engine loop, so
# what differs from the program is the build and the process, not the chunks).
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
chunk = int(sys.argv[2])
t0 = time.perf_counter()
while sim.step_count < sim.total_steps:
    sim.step(chunk)
    _ = sim.particles.position[0, 2]
wall = time.perf_counter() - t0
print(f"{n * sim.step_count / wall / 1e6:.3f}")
PY
# The cost of a call itself: the one-ball case (examples/bouncing-ball), 20 000 steps one at a
# time (a view read after each) against the same in one call, per step.
cat > "$W/call.py" <<'PY'
import sys, time
import grainflow
def per_step(chunk, total=20000):
    sim = grainflow.Simulation.from_case(sys.argv[1], threads=1)
    t0 = time.perf_counter()
    for _ in range(total // chunk):
        sim.step(chunk)
        _ = sim.particles.position[0, 2]
    return (time.perf_counter() - t0) / total
ones, whole = per_step(1), per_step(20000)
print(f"{(ones - whole) * 1e6:.2f}")
PY
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
speed() { awk '/particle-steps\/s on/{for(k=1;k<=NF;k++) if($k=="particle-steps/s") print $(k-1)/1e6}' "$1"; }
: > "$W/cli"; : > "$W/py"; : > "$W/one"
cli() {
  rm -rf "$W/out"
  "$GF" run "$CASE" --set time.t_stop=0.1 -j 1 --out "$W/out" -q > "$W/log"
  speed "$W/log" >> "$W/cli"
}
py() { "$PYTHON" "$W/step.py" "$CASE" 100 >> "$W/py"; }
one() { "$PYTHON" "$W/step.py" "$CASE" 5000 >> "$W/one"; }
for r in $(seq "$RUNS"); do
  case $((r % 3)) in
    1) cli; py; one ;;
    2) py; one; cli ;;
    0) one; cli; py ;;
  esac
  echo "round $r: grainflow run $(tail -1 "$W/cli"), Python by 100 $(tail -1 "$W/py"), in one call $(tail -1 "$W/one")" >&2
done
for r in 1 2 3 4 5; do "$PYTHON" "$W/call.py" "$ROOT/examples/bouncing-ball/case.toml"; done > "$W/call"
CALL=$(median < "$W/call")
CLI=$(median < "$W/cli"); PY=$(median < "$W/py"); ONE=$(median < "$W/one")
OUT=$ROOT/bench/results/$(date -u +%F)-python-overhead.md
ratio() { paste -d' ' "$W/cli" "$1" | awk '{print $2 / $1}' | median | xargs printf '%.3f'; }
{
  echo "# Stepping from Python against grainflow run ($(date -u +%FT%RZ), git $(git rev-parse --short HEAD))"
  echo
  echo "box_hm, 5 000 steps on one thread, $RUNS rounds, each in a rotated order; millions of particle-steps/s."
  echo
  echo "| round | grainflow run | Python, chunks of 100 | Python, one call | by 100 ÷ run | one call ÷ run |"
  echo "|---|---|---|---|---|---|"
  paste -d' ' "$W/cli" "$W/py" "$W/one" |
    awk '{printf "| %d | %.3f | %.3f | %.3f | %.3f | %.3f |\n", NR, $1, $2, $3, $2 / $1, $3 / $1}'
  echo
  echo "Medians: grainflow run $CLI, Python by 100 $PY, in one call $ONE;" \
    "medians of the rounds' ratios: by 100 ÷ run $(ratio "$W/py"), one call ÷ run $(ratio "$W/one")."
  echo
  echo "A call's own cost (\`sim.step(1)\` and a view read, less a step of one call; the one-ball case," \
    "5 repeats, median): $CALL µs (repeats: $(paste -sd' ' "$W/call")). box_hm's 50 calls add" \
    "$(python3 -c "print(f'{50 * $CALL * 1e-6 / (5000 * 10000 / ($CLI * 1e6)) * 100:.4f}')") % to its stepping time."
  echo
  [ -f "$OUT" ] && cat "$OUT"
} > "$W/table"
mv "$W/table" "$OUT"
cat "$OUT"
}
