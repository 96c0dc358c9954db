#!/usr/bin/env bash
# Input-to-screen latency of the game window, measured from outside as a player sees it (docs/latency.md):
# starts the game in a virtual display, waits for it to settle, presses F6 (the albedo view: every pixel changes)
# and screenshots the window back to back until the picture changes; prints the seconds from the key to the log
# line that shows the game saw it ("debug view"), to the first changed screenshot, and the game's frame time.
#
#   docs/latency/measure.sh [-s WxH] [-w SETTLE_S] [-k KEY] -- GLOWBRICK [ARGS...]
# Needs: xvfb xdotool x11-apps imagemagick.
set -u
size=1280x720 settle=60 key=F6
while [ $# -gt 0 ]; do
  case "$1" in
    -s) size=$2; shift 2;;
    -w) settle=$2; shift 2;;
    -k) key=$2; shift 2;;
    --) shift; break;;
    *) break;;
  esac
done
dir=$(mktemp -d)
export XDG_RUNTIME_DIR=$dir; chmod 700 "$dir"
disp=:$((500 + RANDOM % 400))
Xvfb $disp -screen 0 ${size}x24 -nolisten tcp >/dev/null 2>&1 & xpid=$!
sleep 1; export DISPLAY=$disp
NO_COLOR=1 "$@" >"$dir/log.txt" 2>&1 & ppid=$!
sleep "$settle"
win=$(xdotool search --pid $ppid 2>/dev/null | tail -1)
[ -n "$win" ] && xdotool windowfocus "$win" 2>/dev/null
shoot() { xwd -root -silent | convert xwd:- -resize 25% "$1"; }
shoot "$dir/before.png"
t0=$(date +%s.%N)
xdotool key --clearmodifiers "$key"
changed="" n=0
while [ $n -lt 400 ]; do
  shoot "$dir/now.png"; t=$(date +%s.%N); n=$((n + 1))
  diff=$(compare -metric AE -fuzz 10% "$dir/before.png" "$dir/now.png" null: 2>&1 | cut -d' ' -f1)
  if [ "${diff%.*}" -gt 2000 ] 2>/dev/null; then changed=$t; break; fi
done
sleep 2
seen=$(grep -m1 'debug view' "$dir/log.txt" | grep -oE '[0-9]{2}:[0-9]{2}:[0-9]{2}\.[0-9]+' | head -1)
kill $ppid 2>/dev/null; wait $ppid 2>/dev/null; kill $xpid 2>/dev/null; wait $xpid 2>/dev/null
logged=""
[ -n "$seen" ] && logged=$(echo "$(date -u -d "$(date -u +%F) $seen" +%s.%N) - $t0" | bc)
screen=""; [ -n "$changed" ] && screen=$(echo "$changed - $t0" | bc)
frame=$(grep -oE '[0-9.]+ ms\)' "$dir/log.txt" | tail -1)
echo "key->log ${logged:-none} s, key->screen ${screen:-none} s ($n screenshots), $(grep -m1 'input latency' "$dir/log.txt" | sed 's/.*input latency/probe/')"
rm -rf "$dir"
