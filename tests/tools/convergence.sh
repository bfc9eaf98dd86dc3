#!/usr/bin/env bash
# Convergence study: for each scene, every sampling method over several seeds, each run given about
# the same time budget on one thread, with aoview's per-pass --stats against a reference; then
# tests/tools/convergence.py writes the CSV, the log-log charts (PNG and SVG) and the table into --out.
# See docs/accuracy.md for what the outputs mean and how docs/ was made.
#
#   tests/tools/convergence.sh [--aoview BIN] [--exact BIN] [--budget S] [--seeds N] [--size WxH]
#                        [--ref-spp N] [--work DIR] [--out DIR] [--method LABEL[=ARGS]]... SCENE...
#
# --budget is the seconds of one run (one method, one seed; default 10): a 64-spp calibration run
# per method sets the spp that fits it. Reference: aoview-exact's image (64x64 sub-pixel grid) when
# the scene has a closed form, else the mean of two cosine runs of --ref-spp samples each (default
# 32768, seeds 1001 and 1002, 2 threads, one sample per pass: aoview traces one eye ray per pixel
# per pass, so only then does the anti-aliasing converge as fast as the AO), cached in the work
# directory under the aoview binary's checksum, so that it is remade whenever the renderer changes.
# --method adds a method to compare (ARGS: extra aoview arguments separated by spaces, default
# --sampling LABEL, after --sampler random --adaptive off, which ARGS may override); without any,
# the methods are uniform, hemisphere and cosine. Timed runs use
# --threads 1, so that their seconds are comparable between methods and the study leaves the
# machine's other cores alone.
set -euo pipefail

root=$(cd "$(dirname "$0")/../.." && pwd)
aoview=$root/build/aoview
exact=
budget=10
seeds=4
size=160x120
ref_spp=32768
work=
out=$root/docs
methods=()
scenes=()

usage() { sed -n '7,8p' "$0" | sed 's/^# *//' >&2; exit 2; }
while [ $# -gt 0 ]; do
  case $1 in
    --aoview) aoview=$2; shift 2 ;;
    --exact) exact=$2; shift 2 ;;
    --budget) budget=$2; shift 2 ;;
    --seeds) seeds=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    --ref-spp) ref_spp=$2; shift 2 ;;
    --work) work=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --method) methods+=("$2"); shift 2 ;;
    -h|--help) usage ;;
    -*) echo "convergence.sh: unknown option '$1'" >&2; usage ;;
    *) scenes+=("$1"); shift ;;
  esac
done
[ ${#scenes[@]} -gt 0 ] || usage
[ ${#methods[@]} -gt 0 ] || methods=(uniform hemisphere cosine)
exact=${exact:-$(dirname "$aoview")/aoview-exact}
work=${work:-$(dirname "$aoview")/convergence}
for tool in "$aoview" "$exact"; do
  [ -x "$tool" ] || { echo "convergence.sh: $tool is not built (try ninja -C $(dirname "$tool"))" >&2; exit 1; }
done
command -v gnuplot >/dev/null || { echo "convergence.sh: gnuplot is missing (apt-get install gnuplot-nox)" >&2; exit 1; }
mkdir -p "$work" "$out"

# last_seconds_per_spp CSV: seconds / spp of a stats file's last row.
last_seconds_per_spp() { tail -n 1 "$1" | awk -F, '{ printf "%.9f", $3 / $2 }'; }

for scene in "${scenes[@]}"; do
  name=$(basename "${scene%.*}")
  runs=$work/$name
  rm -rf "$runs" && mkdir -p "$runs"

  # Reference: exact, or two cached high-spp runs whose difference measures their noise.
  mapfile -t ref < <(python3 "$root/tests/tools/benchlib.py" reference --aoview "$aoview" --exact "$exact" \
    --size "$size" --spp "$ref_spp" --exact-spp 4096 --work "$work" --args '--sampling cosine --spppp 1 --sampler random --adaptive off' \
    --out "$runs/reference.pfm" "$scene")
  [ ${#ref[@]} -gt 0 ] || exit 1
  ref_args=(--reference-kind "${ref[0]}")
  [ ${#ref[@]} -eq 1 ] || ref_args+=(--reference-pair "${ref[@]:1}")

  # Every method: calibrate its speed, then run each seed for about the budget.
  labels=()
  for method in "${methods[@]}"; do
    label=${method%%=*}
    # Random numbers and every pixel alike, unless the method says otherwise.
    if [ "$method" = "$label" ]; then args=(--sampling "$label"); else read -r -a args <<<"${method#*=}"; fi
    args=(--sampler random --adaptive off "${args[@]}")
    labels+=("$label")
    "$aoview" --headless -q --threads 1 --size "$size" --spp 64 "${args[@]}" --stats "$runs/calibrate.csv" \
      -o "$runs/calibrate.pfm" "$scene"
    spp=$(awk -v b="$budget" -v s="$(last_seconds_per_spp "$runs/calibrate.csv")" \
      'BEGIN { n = int(b / s); print n < 16 ? 16 : n }')
    for seed in $(seq 1 "$seeds"); do
      echo "convergence.sh: $name: $label, seed $seed, $spp spp" >&2
      "$aoview" --headless -q --threads 1 --size "$size" --spp "$spp" --spppp 1 --seed "$seed" "${args[@]}" \
        --stats "$runs/$label-$seed.csv" --reference "$runs/reference.pfm" -o "$runs/$label-$seed.pfm" "$scene"
    done
  done

  python3 "$root/tests/tools/convergence.py" report --name "$name" --runs "$runs" --out "$out" --seeds "$seeds" \
    --budget "$budget" --size "$size" "${ref_args[@]}" --methods "${labels[@]}"
done
