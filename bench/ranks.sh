#!/usr/bin/env bash
# grainflow over MPI ranks against one rank and against LAMMPS (Debian's) on 1 and 2 ranks, on
# the plane-wall yardsticks (box_hm, box_lsd, chute; the settled states of
# bench/compare-peers.sh, written by LAMMPS if missing): particle-steps per second, median of
# RUNS rounds in which every variant runs once, in turn (grainflow 1 rank × 1 thread, 2 ranks ×
# 1 thread, 1 rank × 2 threads, LAMMPS 1 rank, LAMMPS 2 ranks), and the ratios the issue asks
# for: 2 ranks ÷ 1, that ÷ LAMMPS's 2 ÷ 1, 2 ranks ÷ 2 threads. Also each 2-rank run's
# messages and bytes per step and the share of the step spent in the domain stage, from the
# summary. Results go on top of bench/results/<date>-ranks.md.
#
#   bench/ranks.sh            (RUNS=3 NRUN=3000 by default; CASES="box_hm box_lsd chute")
set -euo pipefail
{
cd "$(dirname "$0")/.."
ROOT=$PWD
RUNS=${RUNS:-3}
NRUN=${NRUN:-3000}
CASES=${CASES:-box_hm box_lsd chute}
CARGO=${CARGO:-cargo}
DATA=$ROOT/bench/cases/data
LMPIN=$ROOT/bench/lammps
mkdir -p "$DATA" bench/results
$CARGO build --release --quiet -p grainflow-cli --features mpi
GF=$ROOT/target/release/grainflow
cd "$DATA"
for m in hm lsd; do
  [ -f box_${m}_settled.data ] || lmp -in "$LMPIN/in.box_walls.lmp" -var model $m -var nsettle 25000 -var nrun 0 -log none -screen none
done
[ -f chute_eq.data ] || lmp -in "$LMPIN/in.chute_like.lmp" -var neq 50000 -var nrun 0 -log none -screen none
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
cd "$W"
declare -A LMP_IN=( [box_hm]="$LMPIN/in.box_walls_run.lmp -var model hm -var data $DATA/box_hm_settled.data"
                    [box_lsd]="$LMPIN/in.box_walls_run.lmp -var model lsd -var data $DATA/box_lsd_settled.data"
                    [chute]="$LMPIN/in.chute_like_run.lmp -var data $DATA/chute_eq.data" )
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
gf_speed() { awk '/particle-steps\/s/{for(k=1;k<=NF;k++) if($k=="particle-steps/s") print $(k-1)/1e6}' "$1"; }
MPI="mpirun --allow-run-as-root --oversubscribe"
OUT=$ROOT/bench/results/$(date -u +%F)-ranks.md
{
  echo "## $(date -u +%FT%H:%MZ), git $(git -C "$ROOT" rev-parse --short HEAD), $NRUN steps, medians of $RUNS rounds"
  echo
  echo "Millions of particle-steps/s. $(nproc) cores, $(lscpu | sed -n 's/^Model name: *//p')."
  echo
  echo "| case | gf 1×1 | gf 2 ranks×1 | gf 1×2 threads | LAMMPS 1 | LAMMPS 2 ranks | gf 2r÷1 | ÷ LAMMPS 2r÷1 | 2r ÷ 2 threads | rounds 2r÷1 |"
  echo "|---|---|---|---|---|---|---|---|---|---|"
} > table.md
for c in $CASES; do
  cp "$ROOT/bench/cases/$c.toml" $c.toml
  sed -i "s|file = \"data/|file = \"$DATA/|" $c.toml
  n=$(grep -m1 ' atoms$' "$DATA/$( [ $c = chute ] && echo chute_eq || echo ${c}_settled ).data" | awk '{print $1}')
  dtl=$(awk '/^dt = /{print $3}' $c.toml)
  sed "s|^t_stop = .*|t_stop = $(python3 -c "print($NRUN*$dtl)")|; s|^interval = .*|interval = 1e9|" $c.toml > $c.speed.toml
  lmp_speed() { awk -v n="$n" -v s="$NRUN" '/^Loop time of/{print n*s/$4/1e6; exit}' "$1"; }
  rm -f *.$c.s
  for i in $(seq "$RUNS"); do
    $GF run $c.speed.toml -j 1 --out g11.$i -q > g11.$c.$i.log; gf_speed g11.$c.$i.log >> g11.$c.s
    $MPI -np 2 $GF run $c.speed.toml -j 1 --out g21.$i -q > g21.$c.$i.log; gf_speed g21.$c.$i.log >> g21.$c.s
    $GF run $c.speed.toml -j 2 --out g12.$i -q > g12.$c.$i.log; gf_speed g12.$c.$i.log >> g12.$c.s
    lmp -in ${LMP_IN[$c]} -var nrun "$NRUN" -log l1.$c.$i -screen none; lmp_speed l1.$c.$i >> l1.$c.s
    $MPI -np 2 lmp -in ${LMP_IN[$c]} -var nrun "$NRUN" -log l2.$c.$i -screen none; lmp_speed l2.$c.$i >> l2.$c.s
    rm -rf g11.$i g21.$i g12.$i
  done
  rounds=$(paste -d' ' g21.$c.s g11.$c.s | awk '{printf "%s%.2f", (NR>1?" / ":""), $1/$2}')
  python3 - "$c" "$(median < g11.$c.s)" "$(median < g21.$c.s)" "$(median < g12.$c.s)" "$(median < l1.$c.s)" "$(median < l2.$c.s)" "$rounds" >> table.md <<'PY'
import sys
c, g11, g21, g12, l1, l2, rounds = sys.argv[1], *map(float, sys.argv[2:7]), sys.argv[7]
print(f"| {c} | {g11:.2f} | {g21:.2f} | {g12:.2f} | {l1:.2f} | {l2:.2f} | {g21/g11:.2f} | {(g21/g11)/(l2/l1):.2f} | {g21/g12:.2f} | {rounds} |")
PY
  grep -h "^domain:" g21.$c.$RUNS.log | sed "s/^/- $c, 2 ranks: /" >> notes.md || true
done
{ cat table.md; echo; [ -f notes.md ] && cat notes.md; echo; [ -f "$OUT" ] && cat "$OUT"; } > "$OUT.new"
mv "$OUT.new" "$OUT"
cat table.md
exit
}
