#!/usr/bin/env bash
# Whole runs of the bunny (defaults, 640x480 unless SIZE is set) as one aoview process and as
# aoview-mpi under mpirun on this machine, interleaved REPS times; prints the median wall seconds
# of each configuration and its throughput relative to one 2-thread aoview (the images are the same,
# so the rays are too). Run: bash tests/bench_mpi.sh BUILD_DIR [REPS] (docs/mpi.md).
set -eu
build=${1:?build dir}
reps=${2:-5}
size=${SIZE:-640x480}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_tcp_if_include=lo OMPI_MCA_oob_tcp_if_include=lo
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
configs=("aoview --threads 2" "aoview --threads 1" "mpirun -np 1 --threads 2" "mpirun -np 2 --threads 1"
         "mpirun -np 3 --threads 1" "mpirun -np 2 --threads 2")
run() {
  local words=($1)
  if [ "${words[0]}" = aoview ]; then
    "$build/aoview" --headless -q --size "$size" "${words[1]}" "${words[2]}" -o "$work/x.pfm"
  else
    mpirun --oversubscribe -np "${words[2]}" "$build/aoview-mpi" -q --size "$size" "${words[3]}" "${words[4]}" -o "$work/x.pfm"
  fi
}
for ((k = 0; k < reps; k++)); do
  for c in "${!configs[@]}"; do
    start=$(date +%s%N)
    run "${configs[$c]}"
    echo "$c $(( ($(date +%s%N) - start) / 1000000 ))" >> "$work/times"
  done
done
python3 - "$work/times" "${configs[@]}" <<'PY'
import statistics, sys
times = {}
for line in open(sys.argv[1]):
    c, ms = line.split()
    times.setdefault(int(c), []).append(int(ms) / 1000.0)
names = sys.argv[2:]
base = statistics.median(times[0])
print('| configuration | median s | runs (s) | throughput vs one 2-thread aoview |')
print('|---|---|---|---|')
for c, name in enumerate(names):
    m = statistics.median(times[c])
    print('| `%s` | %.2f | %s | %.0f %% |' % (name, m, ' '.join('%.2f' % t for t in times[c]), 100.0 * base / m))
PY
