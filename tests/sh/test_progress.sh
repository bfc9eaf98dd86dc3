#!/bin/bash
# The headless progress bar as a terminal shows it (aoview under a pty): on the bunny at 640x480
# (defaults: adaptive sampling ends the run before every pixel has --spp) and at 320x240 without
# adaptive sampling (every pixel reaches --spp on the last pass; 256 spp, some 0.3 s on a quiet
# 2-core machine, so that the bar, redrawn at most every 0.1 s, is drawn at least three times),
# every redraw of the bar in order:
# the percentage never decreases and reads 100 % on the last redraw alone; the samples read
# "mean N spp, up to T" with N = T on the last redraw alone, and only where every pixel has T;
# the time left is shown from the second pass on and "~0.0 s left" only at the end. The time
# left's accuracy is tests/unit/test_progress.c's, on recorded runs (a live run's depends on the
# machine's load from one pass to the next).
. "$(dirname "$0")/lib.sh"
bunny=$root/assets/scenes/bunny.scene

# Runs aoview headless with the arguments under a pseudo-terminal, its stderr (the bar) into $1.
under_pty() {
    local out=$1
    shift
    python3 - "$out" "$bin" "$@" <<'EOF'
import os, pty, sys
out = open(sys.argv[1], 'wb')
pid, fd = pty.fork()
if pid == 0:
    os.execv(sys.argv[2], sys.argv[2:])
while True:
    try:
        data = os.read(fd, 65536)
    except OSError:
        break
    if not data:
        break
    out.write(data)
_, status = os.waitpid(pid, 0)
sys.exit(os.waitstatus_to_exitcode(status))
EOF
}

# Checks the bar's redraws in file $1, of a run whose last pass gives every pixel the target
# when $2 is "full".
check_bar() {
    python3 - "$1" "$2" <<'EOF'
import re, sys
text = open(sys.argv[1], 'rb').read().decode('utf-8', 'replace')
full = sys.argv[2] == 'full'
draws = [d for d in re.split(r'[\r\n]', text) if d.startswith('[')]
bar = re.compile(r'\[[# ]{30}\] +(\d+) %  mean (\d+) spp, up to (\d+)  error (\S+(?: %)?)  ([\d.]+) s  (.*?)  [\d.]+ Mrays/s')
problems, last_share = [], -1
parsed = [bar.match(d) for d in draws]
if len(draws) < 3 or not all(parsed):
    sys.exit('FAIL: the bar does not read as expected: %r' % draws[:3])
for k, m in enumerate(parsed):
    share, mean, target, left = int(m.group(1)), int(m.group(2)), int(m.group(3)), m.group(6)
    last = k == len(parsed) - 1
    if share < last_share:
        problems.append('%d %% after %d %%' % (share, last_share))
    if (share == 100) != last:
        problems.append('%d %% on redraw %d of %d' % (share, k + 1, len(parsed)))
    if (mean == target) != (last and full):
        problems.append('mean %d spp, up to %d on redraw %d of %d' % (mean, target, k + 1, len(parsed)))
    if k > 0 and not left:
        problems.append('no time left on redraw %d' % (k + 1))
    if (left == '~0.0 s left') != last:
        problems.append('%r on redraw %d of %d' % (left, k + 1, len(parsed)))
    last_share = share
if problems:
    sys.exit('FAIL: ' + '; '.join(problems[:5]))
print('%d redraws, %s' % (len(parsed), draws[-1].strip()))
EOF
}

under_pty adaptive.txt --headless --size 640x480 -o adaptive.pfm "$bunny" || fail "the adaptive run failed"
check_bar adaptive.txt adaptive || fail "the adaptive run's bar"
under_pty full.txt --headless --size 320x240 --spp 256 --adaptive off -o full.pfm "$bunny" || fail "the full run failed"
check_bar full.txt full || fail "the run without adaptive sampling's bar"
finish
