#!/usr/bin/env bash
# aoview-mpi on localhost: the same image, bit for bit, and --stats decisions as one aoview process
# for 2, 3 and 5 ranks (5 on 2 cores: oversubscribed), with and without adaptive sampling, ranks of
# other --threads included, and only the final image gathered; ranks given another scene or other
# options are refused, naming the rank; a slowed rank traces fewer tiles (the others borrow its
# tiles); a killed rank ends the run with a line naming it and the last safety copy, stated by its
# age; SIGINT to mpirun and SIGTERM to one rank end it with one line and the ranks' image; rank 0's
# window under Xvfb drives every rank (keys and an orbit give one process's image), quits cleanly,
# and without a display the run goes headless.
# Usage: test_mpi.sh equal|differ|slow|killed|sigterm|sigint|window
set -u
mpi_bin=${AO_MPI_BINARY:?AO_MPI_BINARY not set}
command -v mpirun >/dev/null || { echo "SKIP: no mpirun (Debian: openmpi-bin)"; exit 77; }
[ -x "$mpi_bin" ] || { echo "SKIP: $mpi_bin not built"; exit 77; }
if [ "${1:-}" = window ] && [ -z "${AO_UNDER_XVFB:-}" ]; then
  for tool in xvfb-run xdotool; do
    command -v "$tool" >/dev/null || { echo "SKIP: no $tool (Debian: xvfb xdotool)"; exit 77; }
  done
  # A 24-bit screen: xvfb-run's default depth has no OpenGL visual.
  AO_UNDER_XVFB=1 exec xvfb-run -a -s "-screen 0 1280x1024x24" bash "$0" "$@"
fi
# OpenMPI refuses root without these; loopback only, never another network address.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_tcp_if_include=lo OMPI_MCA_oob_tcp_if_include=lo
mpirun=(timeout -k 5 120 mpirun --oversubscribe)
. "$(dirname "$0")/lib.sh"

# max_diff A.pfm B.pfm: the largest |a - b| over all channels, or "size" if the images differ in size.
max_diff() {
  PYTHONPATH=$AO_SOURCE_ROOT/tests/tools python3 - "$1" "$2" <<'PY'
import sys
from benchlib import read_pfm
(wa, ha, a), (wb, hb, b) = read_pfm(sys.argv[1]), read_pfm(sys.argv[2])
print('size' if (wa, ha) != (wb, hb) else max(abs(x - y) for x, y in zip(a, b)))
PY
}

# decisions STATS.csv: the stats rows without the columns that are wall time (seconds, Mrays/s).
decisions() { cut -d, -f1,2,4,5,7- "$1"; }

# same NAME 'ARGS' NP 'RANK ARGS' [MORE...]: one aoview process with ARGS and NP ranks with ARGS
# and RANK ARGS (then MORE, mpirun's other app contexts) give the same image, bit for bit (every
# pixel's sums are its owner's, and what the ranks decide on they combine exactly), and the same
# stats rows (passes, spp, rays, RMSE, error, converged share).
same() {
  local name=$1 args=$2 np=$3 rank_args=$4
  shift 4
  # shellcheck disable=SC2086 # the arguments are words
  "$bin" --headless -q $args --threads 2 -o "$name-1.pfm" --stats "$name-1.csv" || { fail "$name: aoview failed"; return; }
  # shellcheck disable=SC2086
  "${mpirun[@]}" -np "$np" "$mpi_bin" --headless -q $args $rank_args -o "$name-n.pfm" --stats "$name-n.csv" "$@" 2>"$name.err" \
    || { fail "$name: aoview-mpi -np $np failed: $(cat "$name.err")"; return; }
  local d
  d=$(max_diff "$name-1.pfm" "$name-n.pfm")
  [ "$d" = 0.0 ] || fail "$name: -np $np image differs from one process's by $d"
  diff <(decisions "$name-1.csv") <(decisions "$name-n.csv") >/dev/null \
    || fail "$name: -np $np took other decisions: $(diff <(decisions "$name-1.csv") <(decisions "$name-n.csv") | head -4)"
  echo "$name: max |d| = $d over the ranks, $(($(wc -l < "$name-n.csv") - 1)) passes alike"
}

# gathers_of ERR: the image gathers of the run, from aoview-mpi's last line.
gathers_of() { sed -n 's/.* bytes in \([0-9]*\) image gathers.*/\1/p' "$1"; }

# tiles_of RANK ERR: the tiles RANK traced, from the "tiles traced by rank" line.
tiles_of() { sed -n "s/.*tiles traced by rank .*\b$1: \([0-9]*\).*/\1/p" "$2"; }

# rank_pid PID RANK: the pid of that rank among the descendants of PID (timeout, then mpirun).
rank_pid() {
  local p
  for p in $(pgrep -P "$(pgrep -P "$1")"); do
    if tr '\0' '\n' < "/proc/$p/environ" 2>/dev/null | grep -qx "OMPI_COMM_WORLD_RANK=$2"; then echo "$p"; return; fi
  done
}

# A render far too long to finish, started in the background with its --stats and ARGS; waits for
# PASSES passes (3 by default). PFM: mpirun kills the ranks a second after its SIGTERM, and a PNG
# takes half of that to write (OSMesa and LLVM load), too much of it in the sanitizer builds on a
# busy machine.
start_long() {
  local passes=${1:-3}
  shift $(($# > 0))
  rm -f long.pfm long.csv
  "${mpirun[@]}" -np 3 "$mpi_bin" --headless --spp 1000000 --size 96x64 --threads 1 -o long.pfm --stats long.csv "$@" \
    2>long.err &
  long_pid=$!
  for _ in $(seq 300); do [ -f long.csv ] && [ "$(wc -l < long.csv)" -gt "$passes" ] && break; sleep 0.1; done
}

# complete_pfm FILE W H: a whole colour PFM of W x H, no temporary file beside it.
complete_pfm() {
  local header="PF"$'\n'"$2 $3"$'\n'"-1.0"$'\n'
  [ -f "$1" ] && [ "$(stat -c %s "$1")" = $(( ${#header} + 12 * $2 * $3 )) ] && [ "$(head -c 2 "$1")" = PF ] &&
    [ -z "$(ls -A | grep -v -x -e long.pfm -e long.csv -e long.err)" ]
}

# viewer NAME COMMAND...: starts COMMAND (a viewer) in the background with its output in NAME.out
# and NAME.err, and waits for its window, then a moment for it to take keys: $viewer_pid, $wid.
viewer() {
  local name=$1
  shift
  "$@" >"$name.out" 2>"$name.err" &
  viewer_pid=$!
  wid=$(timeout 30 xdotool search --sync --onlyvisible --name '^aoview') || { fail "$name: no window: $(cat "$name.err")"; return 1; }
  wid=${wid%%$'\n'*}
  sleep 1
}

# end_viewer: after a failure, ends the viewer (mpirun ends its ranks), so that the next window
# found is the next viewer's.
end_viewer() {
  kill "$viewer_pid" 2>/dev/null
  wait "$viewer_pid" 2>/dev/null
}

# title_shows REGEX: polls the window's title until it matches (true), for at most 20 s.
title_shows() {
  for _ in $(seq 400); do
    [[ $(xdotool getwindowname "$wid" 2>/dev/null) =~ $1 ]] && return 0
    sleep 0.05
  done
  return 1
}

wait_title() { title_shows "$1" || { fail "title never matched /$1/: $(xdotool getwindowname "$wid" 2>/dev/null)"; return 1; }; }

press() { xdotool windowfocus --sync "$wid" key --delay 20 "$@" 2>/dev/null; }

# quit NAME: Q, then the viewer (every rank, for aoview-mpi) must end with status 0 within 10 s.
quit() {
  press q
  for _ in $(seq 100); do kill -0 "$viewer_pid" 2>/dev/null || break; sleep 0.1; done
  if kill -0 "$viewer_pid" 2>/dev/null; then
    fail "$1: still running 10 s after Q"
    end_viewer
    return 1
  fi
  wait "$viewer_pid" || fail "$1: ended with status $? after Q: $(cat "$1.err")"
}

# drive NAME: from hemisphere sampling with AA, C, A, a resize of the window to 640x400 (the 96x64
# image's pixel size is 8: 80x50 pixels) and one orbit (a drag as a single mouse move, so that
# both viewers turn the camera alike); once the run has finished (64 spp), S saves the image
# shown (NAME.pfm), Q.
drive() {
  local name=$1
  wait_title " — hemisphere — AA on — " || return
  # C again if the first key, right after the window showed, went astray (C twice is C once).
  press c
  title_shows " — cosine — AA on — " || { press c && wait_title " — cosine — AA on — "; } || return
  press a
  wait_title " — cosine — AA off — " || return
  xdotool windowsize "$wid" 640 400
  wait_title " — 80x50 — cosine — AA off — " || return
  xdotool mousemove --window "$wid" 300 200 && sleep 0.2 && xdotool mousedown 1 && sleep 0.2 &&
    xdotool mousemove --window "$wid" 360 220 && sleep 0.2 && xdotool mouseup 1
  wait_title " — finished — " || return
  sleep 0.5
  press s
  for _ in $(seq 200); do [ -s aoview-1.pfm ] && break; sleep 0.05; done
  mv aoview-1.pfm "$name.pfm" 2>/dev/null || fail "$name: S saved no image"
  rm -f aoview-1.png
  quit "$name"
}

case ${1:?equal, differ, slow, killed, sigterm, sigint or window} in
equal)
  # The defaults (adaptive sampling, auto passes, Sobol) with a reference for the RMSE column, on
  # 2, 3 and 5 ranks (5 oversubscribe the 2 cores), and the same without adaptive sampling.
  "$bin" --headless -q --size 160x120 --spp 64 --seed 7 -o ref.pfm || fail "reference failed"
  for np in 2 3 5; do
    same "defaults$np" "--size 160x120 --reference ref.pfm" "$np" ""
    same "uniform$np" "--size 160x120 --spp 128 --adaptive off" "$np" ""
  done
  # Ranks with other thread counts (MPMD): a target error on 1 + 2, the defaults on 1 + 1 + 3.
  same target "--size 160x120 --target-error 0.02" 1 "--threads 1" : -np 2 "$mpi_bin" --threads 2 -q --size 160x120 --target-error 0.02
  same threads "--size 160x120" 2 "--threads 1" : -np 1 "$mpi_bin" --threads 3 -q --size 160x120
  same textbook "--size 120x90 --spp 32 --sampler random --spppp 4 --adaptive off --sampling uniform" 3 ""
  # Headless, a run shorter than the safety copy's 5 s gathers the image once, at the end.
  "${mpirun[@]}" -np 3 "$mpi_bin" --headless --size 160x120 --threads 1 -o once.pfm 2>once.err
  [ "$(gathers_of once.err)" = 1 ] || fail "a 3-rank headless run gathered the image $(gathers_of once.err) times: $(cat once.err)"
  ;;
differ)
  # Ranks given other settings or another scene would render another image: refused, once, with
  # status 2, naming the first rank that differs.
  spheres=$AO_SOURCE_ROOT/assets/scenes/spheres.scene
  "${mpirun[@]}" -np 2 "$mpi_bin" --headless --size 96x64 --spp 64 -o mismatch.pfm : -np 1 "$mpi_bin" --size 96x64 --spp 32 \
    2>mismatch.err
  status=$?
  [ "$status" = 2 ] && [ "$(grep -c "^aoview-mpi: rank 2 was given other options than rank 0" mismatch.err)" = 1 ] &&
    [ ! -e mismatch.pfm ] || fail "rank 2 with other --spp was not refused once (status $status): $(cat mismatch.err)"
  # Another albedo on rank 1 only: the same geometry, camera and options, another image.
  sed 's/albedo 0.8 *# resting/albedo 0.3 # resting/' "$spheres" > other.scene
  cmp -s "$spheres" other.scene && fail "other.scene is not another scene"
  "${mpirun[@]}" -np 1 "$mpi_bin" --headless --size 96x64 --spp 16 -o mismatch.pfm "$spheres" : \
    -np 2 "$mpi_bin" --size 96x64 --spp 16 other.scene 2>mismatch.err
  status=$?
  [ "$status" = 2 ] && [ "$(grep -c "^aoview-mpi: rank 1 loaded another scene than rank 0" mismatch.err)" = 1 ] &&
    [ ! -e mismatch.pfm ] || fail "rank 1 with another albedo was not refused once (status $status): $(cat mismatch.err)"
  # Two placements of the bunny (flattened: scene.h's AUTO rule) that differ on rank 1 only in one
  # placement's translation, by 0.001: the same file, other positions, another image.
  bunny=$AO_SOURCE_ROOT/assets/bunny.obj
  printf 'camera eye 0 8 30 target 0 0 0\nmesh %s\nmesh %s translate 12 0 0\n' "$bunny" "$bunny" > placed.scene
  printf 'camera eye 0 8 30 target 0 0 0\nmesh %s\nmesh %s translate 12.001 0 0\n' "$bunny" "$bunny" > moved.scene
  "${mpirun[@]}" -np 1 "$mpi_bin" --headless --size 96x64 --spp 16 -o mismatch.pfm placed.scene : \
    -np 1 "$mpi_bin" --size 96x64 --spp 16 moved.scene 2>mismatch.err
  status=$?
  [ "$status" = 2 ] && [ "$(grep -c "^aoview-mpi: rank 1 loaded another scene than rank 0" mismatch.err)" = 1 ] &&
    [ ! -e mismatch.pfm ] || fail "rank 1 with another placement was not refused once (status $status): $(cat mismatch.err)"
  # The scene missing on rank 2 alone: its own line names it.
  "${mpirun[@]}" -np 2 "$mpi_bin" --headless --size 96x64 --spp 16 -o mismatch.pfm "$spheres" : \
    -np 1 "$mpi_bin" --size 96x64 --spp 16 missing.scene 2>mismatch.err
  status=$?
  [ "$status" = 1 ] && [ "$(grep -c "^aoview-mpi: rank 2: .*missing.scene" mismatch.err)" = 1 ] && [ ! -e mismatch.pfm ] ||
    fail "a scene missing on rank 2 was not reported once, naming it (status $status): $(cat mismatch.err)"
  # A scene's `image` line is charged to every rank's budget (each allocated 3.1 GB for 8192x8192
  # under --scene-budget 16M): refused once; and --stats naming the scene, before anything loads.
  printf 'image 8192 8192\nsphere center 0 0 0 radius 1\n' > image.scene
  "${mpirun[@]}" -np 2 "$mpi_bin" --headless --spp 1 --scene-budget 16M -o mismatch.pfm image.scene 2>mismatch.err
  status=$?
  [ "$status" = 1 ] && [ "$(grep -c "image.scene:1: 'image' 8192x8192: its buffers need about 4.8 GiB" mismatch.err)" = 1 ] &&
    [ ! -e mismatch.pfm ] || fail "an image line past the budget was not refused once (status $status): $(cat mismatch.err)"
  # The scene budget is rank 0's on every rank (by default its machine's): rank 1 given one that
  # alone would refuse the mesh (28,800 triangles: about 2.5 MiB) loads it as rank 0 does, and the
  # image is one process's.
  python3 "$AO_SOURCE_ROOT/tests/tools/mesh_convert.py" --grid 120 grid.obj || fail "no grid"
  "${mpirun[@]}" -np 1 "$mpi_bin" --headless -q --size 96x64 --spp 16 --threads 1 -o budget.pfm grid.obj : \
    -np 1 "$mpi_bin" --size 96x64 --spp 16 --threads 1 --scene-budget 1M grid.obj 2>budget.err ||
    fail "rank 1 given a smaller --scene-budget: $(cat budget.err)"
  "$bin" --headless -q --size 96x64 --spp 16 --threads 2 -o budget-1.pfm grid.obj || fail "aoview failed"
  d=$(max_diff budget-1.pfm budget.pfm 2>/dev/null)
  [ "$d" = 0.0 ] || fail "the ranks under rank 0's budget differ from one process by ${d:-?}"
  cp "$spheres" copy.scene
  "${mpirun[@]}" -np 2 "$mpi_bin" --headless --size 96x64 --spp 16 --stats copy.scene -o mismatch.pfm copy.scene \
    2>mismatch.err
  status=$?
  [ "$status" = 1 ] && [ "$(grep -c "^--stats: copy.scene is also the scene" mismatch.err)" = 1 ] &&
    cmp -s copy.scene "$spheres" || fail "--stats onto the scene was not refused once (status $status): $(cat mismatch.err)"
  ;;
slow)
  # Rank 1 sleeps 3 ms a tile (AO_MPI_TEST_DELAY_US, read by src/mpi/cluster.c for this test only),
  # some 30 times a 16x16 tile's cost at these settings here. Rank 0 then traces most tiles: once
  # its own are done it borrows rank 1's untraced ones in proportion to their speeds (about 30 to
  # 1), so rank 1 traces the few it begins before a loan comes; without loans it would trace its
  # half. The bound, rank 1 below 1/4 of the tiles, leaves a wide margin for a busy machine.
  same slow "--size 160x120 --spp 128" 1 "--threads 1" : -np 1 env AO_MPI_TEST_DELAY_US=3000 "$mpi_bin" -q --size 160x120 --spp 128 --threads 1
  "${mpirun[@]}" -np 1 "$mpi_bin" --headless --size 160x120 --spp 128 --threads 1 -o slow.pfm : \
    -np 1 env AO_MPI_TEST_DELAY_US=3000 "$mpi_bin" --size 160x120 --spp 128 --threads 1 -o slow.pfm 2>slow.err
  fast=$(tiles_of 0 slow.err) slow=$(tiles_of 1 slow.err)
  echo "tiles: rank 0 $fast, slowed rank 1 $slow"
  [ -n "$fast" ] && [ -n "$slow" ] && [ $((4 * slow)) -lt $((fast + slow)) ] \
    || fail "the slowed rank traced $slow of $((fast + slow)) tiles: $(cat slow.err)"
  ;;
killed)
  # Safety copies every 0.3 s; the kill comes 4 s in at least, so that an age counted from the
  # start would show (the copy is some 1.5 s old: up to 0.3 s, mpirun's second, rank 0's 0.2 s). Passes of 4 spp without adaptive sampling: the copy at N spp is one aoview
  # process's image at --spp N, bit for bit. mpirun stops the others a second after the loss.
  uniform=(--spppp 4 --adaptive off)
  start_long 3 --safety-copy 0.3 "${uniform[@]}"
  sleep 4
  victim=$(rank_pid "$long_pid" 2)
  [ -n "$victim" ] || fail "rank 2 not found among mpirun's children"
  kill -KILL "$victim"
  wait "$long_pid"
  status=$?
  # mpirun's status is the first failed rank's (docs/mpi.md): 128 + SIGKILL; rank 0 exits 1.
  [ "$status" = 137 ] || fail "a killed rank ended mpirun with status $status, expected 137"
  line=$(grep "^aoview: rank 2 lost (killed or crashed); the last copy, gathered [0-9.]* s ago, stopped at [0-9]* spp" long.err)
  [ -n "$line" ] || fail "no line naming rank 2 and the copy's age: $(cat long.err)"
  age=$(sed -n 's/.* gathered \([0-9.]*\) s ago.*/\1/p' <<<"$line")
  spp=$(sed -n 's/.* stopped at \([0-9]*\) spp/\1/p' <<<"$line")
  echo "lost rank 2: the copy was ${age:-?} s old, at ${spp:-?} spp"
  python3 -c "import sys; sys.exit(0 if 0 <= float('$age') <= 3.5 else 1)" 2>/dev/null ||
    fail "the copy's stated age ${age:-?} s is not that of a copy gathered every 0.3 s"
  complete_pfm long.pfm 96 64 || fail "no complete image after the killed rank: $(ls -A)"
  if [ -n "$spp" ]; then
    "$bin" --headless -q --size 96x64 --threads 2 --spp "$spp" "${uniform[@]}" -o copy.pfm
    d=$(max_diff copy.pfm long.pfm)
    [ "$d" = 0.0 ] || fail "the written image is not the copy at $spp spp: max |d| = $d from one process's"
    echo "the written image is one process's at $spp spp: max |d| = $d"
  fi
  ;;
sigterm)
  # SIGTERM to rank 2 alone: the run ends at once (not after rank 2's linger), naming rank 2,
  # with status 143 and the image the ranks hold.
  start_long
  victim=$(rank_pid "$long_pid" 2)
  [ -n "$victim" ] || fail "rank 2 not found among mpirun's children"
  started=$(date +%s.%N)
  kill -TERM "$victim"
  wait "$long_pid"
  status=$?
  took=$(python3 -c "print('%.1f' % ($(date +%s.%N) - $started))")
  echo "SIGTERM to rank 2: the run ended ${took} s later, status $status"
  [ "$status" = 143 ] || fail "SIGTERM to rank 2 ended the run with status $status: $(cat long.err)"
  python3 -c "import sys; sys.exit(0 if $took < 3 else 1)" || fail "the run took $took s to end after SIGTERM to rank 2"
  grep -q "^aoview: rank 2 interrupted by SIGTERM at [0-9]* spp" long.err || fail "no line naming rank 2: $(cat long.err)"
  grep -q "lost" long.err && fail "a rank named lost after SIGTERM to rank 2: $(cat long.err)"
  complete_pfm long.pfm 96 64 || fail "no complete image after SIGTERM to rank 2: $(ls -A)"
  # Its spp is the most samples a pixel has, as every stats row's and a safety copy's (it said the
  # fewest): at least the last row's.
  spp=$(sed -n 's/^aoview: rank 2 interrupted by SIGTERM at \([0-9]*\) spp.*/\1/p' long.err)
  [ -n "$spp" ] && [ "$spp" -ge "$(tail -n 1 long.csv | cut -d, -f2)" ] ||
    fail "the interrupted image says $spp spp, the last stats row $(tail -n 1 long.csv | cut -d, -f2)"
  ;;
sigint)
  start_long
  # To mpirun itself, as Ctrl-C at a terminal does: timeout would pass it on and send it to its
  # process group as well, and mpirun takes a second SIGINT for "abort now".
  kill -INT "$(pgrep -P "$long_pid")"
  wait "$long_pid"
  status=$?
  # Open MPI ends an interrupted mpirun as an aborted job, status 1, whatever its ranks' (rank 0: 143).
  [ "$status" = 1 ] || fail "SIGINT to mpirun ended it with status $status, expected 1 (docs/mpi.md)"
  grep -q "^aoview: interrupted by SIGTERM at [0-9]* spp" long.err || fail "no interruption line: $(cat long.err)"
  grep -q "lost" long.err && fail "a rank named lost after SIGINT: $(cat long.err)"
  complete_pfm long.pfm 96 64 || fail "no complete image after SIGINT: $(ls -A)"
  ;;
window)
  spheres=$AO_SOURCE_ROOT/assets/scenes/spheres.scene
  small=(--size 96x64 --spp 64 --adaptive off --sampling hemisphere "$spheres")
  # Rank 0 sleeps 2 ms a tile (AO_MPI_TEST_DELAY_US), so that rank 1 traces most tiles: had it
  # not taken up the window's sampling, AA and camera, the image would not be one process's.
  viewer one "$bin" --threads 2 "${small[@]}" && { drive one || end_viewer; }
  viewer ranks "${mpirun[@]}" -np 1 env AO_MPI_TEST_DELAY_US=2000 "$mpi_bin" --threads 1 "${small[@]}" : \
    -np 1 "$mpi_bin" --threads 1 "${small[@]}" && { drive ranks || end_viewer; }
  d=$(max_diff one.pfm ranks.pfm 2>/dev/null)
  traced=$(tiles_of 1 ranks.err)
  echo "after C, A, a resize and an orbit: max |d| = ${d:-?} from one process; tiles traced by rank 0 $(tiles_of 0 ranks.err), rank 1 ${traced:-?}"
  [ "$d" = 0.0 ] || fail "the ranks' image after C, A, a resize and an orbit differs from one process's by ${d:-?}"
  [ "${traced:-0}" -gt 0 ] || fail "rank 1 traced no tile: $(cat ranks.err)"
  "$bin" --headless -q --size 80x50 --spp 64 --adaptive off --sampling cosine --no-aa -o still.pfm "$spheres"
  [ "$(max_diff one.pfm still.pfm)" != 0.0 ] || fail "the drag did not orbit the camera"

  # Q mid-pass (after V, which aoview-mpi has not), and Q while paused: every rank ends, status 0.
  viewer long "${mpirun[@]}" -np 2 "$mpi_bin" --threads 1 --size 160x120 --spp 1000000 --spppp 256 "$spheres" &&
    { wait_title " — pass ([2-9]|[1-9][0-9]+) — " && press v && sleep 0.3 && quit long || end_viewer; }
  grep -q "V compares two configurations; not available here" long.out || fail "V said nothing: $(cat long.out)"
  viewer paused "${mpirun[@]}" -np 2 "$mpi_bin" --threads 1 --size 160x120 --spp 1000000 "$spheres" &&
    { wait_title " — pass ([2-9]|[1-9][0-9]+) — " && press space && wait_title " — paused" && quit paused || end_viewer; }

  # No display: one line, then headless to the default output, as aoview does.
  rm -f aoview.png
  env -u DISPLAY "${mpirun[@]}" -np 2 "$mpi_bin" -q --size 96x64 --spp 16 "$spheres" 2>nodisplay.err ||
    fail "no display: status $?: $(cat nodisplay.err)"
  grep -q "^aoview: no display available; rendering headless to aoview.png" nodisplay.err && [ -s aoview.png ] ||
    fail "no display: $(cat nodisplay.err)"
  ;;
esac
[ "$failures" = 0 ] && echo "all passed"
finish
