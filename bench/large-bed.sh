#!/usr/bin/env bash
# Speed per particle of the 1 000 000-particle bed against its 10 000-particle original
# (cases/box_hm_1m.toml is the exact 10 x 10 replica of cases/box_hm_periodic.toml), for
# grainflow on 1 thread and for LAMMPS on one core (lammps/in.box_periodic_run.lmp: the same
# law, time step and neighbour settings), with grainflow's peak memory per particle. RUNS
# rounds, each running all four in turn (so that a slow spell of the machine falls on all of
# them alike): the 10 k beds NRUN10K steps, the 1 M beds NRUN1M steps. Prints particle-steps
# per second (medians) and each code's 1 M ÷ 10 k ratio, and puts the table on top of
# bench/results/<date>-<host>.md. Needs the data files of compare-peers.sh and
# make-large-bed.py (it writes the 1 M bed if missing) and LAMMPS (`lmp`).
#
#   bench/large-bed.sh            (RUNS=2 NRUN10K=2000 NRUN1M=200 by default)
set -euo pipefail
# The whole script is one block, read before it runs and ending in `exit`, so that bash (which
# reads a script as it goes) never reads on: an edit of this file during a run cannot change
# what the run does.
{
cd "$(dirname "$0")/.."
ROOT=$PWD
RUNS=${RUNS:-2}
NRUN10K=${NRUN10K:-2000}
NRUN1M=${NRUN1M:-200}
DATA=$ROOT/bench/cases/data
[ -f "$DATA/box_hm_settled.data" ] || { echo "missing $DATA/box_hm_settled.data: run bench/compare-peers.sh first" >&2; exit 2; }
[ -f "$DATA/box_hm_1m.data" ] || python3 bench/make-large-bed.py "$DATA/box_hm_settled.data" 10 "$DATA/box_hm_1m.data" 0
command -v lmp >/dev/null || { echo "LAMMPS (lmp) is missing: apt-get install -y lammps" >&2; exit 2; }
cargo build --release --quiet
GF=$ROOT/target/release/grainflow
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
case_for() { # case name, steps -> a copy running that many steps
  local dt; dt=$(awk '/^dt = /{print $3}' "$ROOT/bench/cases/$1.toml")
  sed "s|file = \"data/|file = \"$DATA/|; s|^t_stop = .*|t_stop = $(python3 -c "print($2*$dt)")|; s|^interval = .*|interval = 1e9|" \
    "$ROOT/bench/cases/$1.toml" > "$W/$1.toml"
}
case_for box_hm_periodic "$NRUN10K"
case_for box_hm_1m "$NRUN1M"
gf_speed() { awk '/particle-steps\/s/{for(k=1;k<=NF;k++) if($k=="particle-steps/s") print $(k-1)/1e6}'; }
lmp_speed() { awk -v n="$2" -v s="$3" '/^Loop time of/{print n*s/$4/1e6; exit}' "$1"; }
cd "$W"
for i in $(seq "$RUNS"); do
  "$GF" run box_hm_periodic.toml -j 1 -q --overwrite --out gf10k | gf_speed >> gf10k.speeds
  /usr/bin/time -f "%M" -o rss.$i "$GF" run box_hm_1m.toml -j 1 -q --overwrite --out gf1m | gf_speed >> gf1m.speeds
  cat rss.$i >> gf1m.rss
  lmp -in "$ROOT/bench/lammps/in.box_periodic_run.lmp" -var data "$DATA/box_hm_settled.data" -var nrun "$NRUN10K" -log l10k.$i -screen none
  lmp_speed l10k.$i 10000 "$NRUN10K" >> l10k.speeds
  lmp -in "$ROOT/bench/lammps/in.box_periodic_run.lmp" -var data "$DATA/box_hm_1m.data" -var nrun "$NRUN1M" -log l1m.$i -screen none
  lmp_speed l1m.$i 1000000 "$NRUN1M" >> l1m.speeds
done
ke_l=$(awk '/^Step/{f=1;next} f && $1=='"$NRUN1M"' {print $3; exit}' l1m.1)
ke_g=$(awk -F, -v s="$NRUN1M" '$1==s {print $3}' gf1m/timeseries.csv)
section=$W/section.md
{
  echo "# 1 000 000 particles against 10 000, grainflow and LAMMPS, $(date -u +%Y-%m-%dT%H:%MZ)"
  echo
  echo "Machine: $(lscpu | awk -F: '/Model name/{gsub(/^ +/,"",$2); print $2}'), $(nproc) cores, $(free -g | awk '/Mem/{print $2}') GiB; one core each."
  echo "The Hertz–Mindlin bed with periodic sides (cases/box_hm_periodic.toml, lammps/in.box_periodic_run.lmp) and its exact"
  echo "10 × 10 replica; $RUNS rounds, all four runs in turn in each; 10 k: $NRUN10K steps, 1 M: $NRUN1M steps."
  echo
  echo "| code | 10 k | 1 M | 1 M ÷ 10 k | runs (10 k; 1 M) |"
  echo "|---|---|---|---|---|"
  for c in gf lmp; do
    a=$( [ $c = gf ] && cat gf10k.speeds || cat l10k.speeds ); b=$( [ $c = gf ] && cat gf1m.speeds || cat l1m.speeds )
    m10=$(echo "$a" | median); m1=$(echo "$b" | median)
    two() { printf "%.2f" "$1"; }
    runs() { for v in "$@"; do printf "%.2f\n" "$v"; done | paste -sd/; }
    echo "| $( [ $c = gf ] && echo "grainflow, 1 thread" || echo LAMMPS ) | $(two "$m10") | $(two "$m1") | $(python3 -c "print(f'{$m1/$m10:.2f}')") | $(runs $a); $(runs $b) |"
  done
  echo
  echo "Millions of particle-steps per second (medians). grainflow's 1 M bed peaked at $(sort -g gf1m.rss | tail -1) KiB"
  echo "($(python3 -c "print(round($(sort -g gf1m.rss | tail -1)*1024/1e6))") bytes per particle). Kinetic energy after $NRUN1M steps of the 1 M bed: LAMMPS $ke_l, grainflow $(printf "%.8g" "$ke_g")."
} > "$section"
out="$ROOT/bench/results/$(date +%Y-%m-%d)-$(hostname).md"
if [ -f "$out" ]; then { cat "$section"; echo; cat "$out"; } > "$out.tmp"; else cp "$section" "$out.tmp"; fi
mv "$out.tmp" "$out"
cat "$section"
exit
}
