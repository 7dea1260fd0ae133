#!/usr/bin/env bash
# grainflow over MPI ranks on the mesh yardsticks of bench/compare-mesh.sh (the drum, 15 750
# spheres in a turning 12 096-triangle mesh; hopper_10k, 30 000 spheres discharging from a
# 9 976-triangle hopper), against one rank, one rank on 2 threads, and LIGGGHTS's own gain
# from 2 ranks in the same session (LAMMPS has no mesh walls). The same windows as
# compare-mesh.sh: grainflow's untimed steps are one run that writes a checkpoint, every timed
# run restarts from it (on any rank count). Particle-steps per second, median of RUNS rounds in
# which every variant runs once, in turn. Results go on top of
# bench/results/<date>-ranks-mesh.md.
#
#   bench/ranks-mesh.sh       (RUNS=3; CASES="drum hopper_10k"; SETTLED= the peer's states)
set -euo pipefail
{
cd "$(dirname "$0")/.."
ROOT=$PWD
RUNS=${RUNS:-3}
CASES=${CASES:-drum hopper_10k}
MP=$ROOT/bench/liggghts-mesh
SETTLED=${SETTLED:-$ROOT/../shared/peers/liggghts-mesh}
HOPPER_WARM=500; HOPPER_RUN=2000; DRUM_WARM=1000; DRUM_RUN=2000; DT=2e-5
cargo build --release --quiet -p grainflow-cli --features mpi
GF=$ROOT/target/release/grainflow
MPI="mpirun --allow-run-as-root --oversubscribe"
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
mkdir -p "$W/data"
python3 "$MP/make_geometry.py" "$W/data" >/dev/null
ln -s "$SETTLED"/*.data "$W/data/"
cd "$W"
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
gf_speed() { awk '/particle-steps\/s on/{for(k=1;k<=NF;k++) if($k=="particle-steps/s") print $(k-1)/1e6}' "$1"; }
lig_speed() { awk -v s="$2" '/^Loop time of/{t=$4; for(k=1;k<=NF;k++) if($k=="with") n=$(k+1)} END {print n*s/t/1e6}' "$1"; }
OUT=$ROOT/bench/results/$(date -u +%F)-ranks-mesh.md
{
  echo "## $(date -u +%FT%H:%MZ), git $(git -C "$ROOT" rev-parse --short HEAD), medians of $RUNS rounds"
  echo
  echo "Millions of particle-steps/s. $(nproc) cores, $(lscpu | sed -n 's/^Model name: *//p'). LIGGGHTS with OMP_NUM_THREADS=1."
  echo
  echo "| case | gf 1×1 | gf 2 ranks×1 | gf 1×2 threads | LIGGGHTS 1 | LIGGGHTS 2 ranks | gf 2r÷1 | ÷ LIGGGHTS 2r÷1 | 2r ÷ 2 threads | rounds 2r÷1 |"
  echo "|---|---|---|---|---|---|---|---|---|---|"
} > table.md
: > notes.md
for c in $CASES; do
  case $c in
    hopper_*) m=${c#hopper_}; nw=$HOPPER_WARM; nr=$HOPPER_RUN
              lig_in="$MP/in.hopper_discharge.liggghts -var mesh $m -var data data/hopper_${m}_settled.data" ;;
    drum)     nw=$DRUM_WARM; nr=$DRUM_RUN; lig_in="$MP/in.drum_rotate.liggghts -var data data/drum_rotating.data" ;;
  esac
  case_t() { sed "s|^t_stop = .*|t_stop = $(python3 -c "print(($1 - 0.5) * $DT)")|; s|^interval = .*|interval = 1e9|" "$ROOT/bench/cases/$c.toml"; }
  case_t $((nw + 1)) > $c.warm.toml
  case_t $((nw + nr)) > $c.timed.toml
  $GF run $c.warm.toml -j 1 --out gf.$c.warm -q --checkpoint-every $nw > gf.$c.warm.log
  # $1: what starts the program ("" or mpirun's words); the rest: grainflow run's options.
  timed() { local start=$1; shift; $start $GF run $c.timed.toml -q --restart gf.$c.warm/checkpoint.gfc --accept-changed-case "$@"; }
  rm -f *.$c.s
  for i in $(seq "$RUNS"); do
    timed "" -j 1 --out g11.$c.$i > g11.$c.$i.log; gf_speed g11.$c.$i.log >> g11.$c.s
    timed "$MPI -np 2" -j 1 --out g21.$c.$i > g21.$c.$i.log; gf_speed g21.$c.$i.log >> g21.$c.s
    timed "" -j 2 --out g12.$c.$i > g12.$c.$i.log; gf_speed g12.$c.$i.log >> g12.$c.s
    for np in 1 2; do
      OMP_NUM_THREADS=1 $MPI -np $np liggghts -in $lig_in -var mdir data -var idir "$MP" -var nwarm $nw -var nrun $nr \
        -log l$np.$c.$i > l$np.$c.$i.screen 2>&1
      lig_speed l$np.$c.$i $nr >> l$np.$c.s
    done
  done
  rounds=$(paste -d' ' g21.$c.s g11.$c.s | awk '{printf "%s%.2f", (NR > 1 ? " / " : ""), $1 / $2}')
  python3 - "$c" "$(median < g11.$c.s)" "$(median < g21.$c.s)" "$(median < g12.$c.s)" \
    "$(median < l1.$c.s)" "$(median < l2.$c.s)" "$rounds" >> table.md <<'PY'
import sys
c, g11, g21, g12, l1, l2, rounds = sys.argv[1:]
g11, g21, g12, l1, l2 = map(float, (g11, g21, g12, l1, l2))
print(f"| {c} | {g11:.2f} | {g21:.2f} | {g12:.2f} | {l1:.2f} | {l2:.2f} | {g21/g11:.2f} | {(g21/g11)/(l2/l1):.2f} | {g21/g12:.2f} | {rounds} |")
PY
  echo "- $c, 2 ranks: $(grep '^domain:' g21.$c.1.log)" >> notes.md
  echo "- $c, 2 ranks: $(grep '^stages:' g21.$c.1.log)" >> notes.md
  echo "- $c, 1 rank: $(grep '^stages:' g11.$c.1.log)" >> notes.md
done
if [ -f "$OUT" ]; then tail -n +3 "$OUT" > earlier.md; else : > earlier.md; fi
{ printf '# MPI ranks on the mesh yardsticks (bench/ranks-mesh.sh)\n\n'
  cat table.md; echo; cat notes.md; echo; cat earlier.md; } > new.md
mv new.md "$OUT"
cat table.md notes.md
exit
}
