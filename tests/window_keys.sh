#!/usr/bin/env bash
# Runs inside xvfb-run (render_cli_test.sh): opens the demo window, sends it
# real key presses through XTEST (xdotool) and lets it run out its frames.
# Usage: window_keys.sh path/to/terrain out_folder log_file
T=$1
out=$2
log=$3
"$T" demo --scene erosion --size 32 --width 320 --height 200 --frames 1000 --out "$out" >"$log" 2>&1 &
pid=$!
wid=""
for _ in $(seq 100); do
  wid=$(xdotool search --name "terrain demo" 2>/dev/null | head -1)
  [ -n "$wid" ] && break
  sleep 0.1
done
[ -n "$wid" ] || { kill "$pid"; echo "window_keys: no window" >>"$log"; exit 1; }
xdotool mousemove --window "$wid" 160 100   # X gives the keys to the window under the pointer
sleep 0.5
# Each key waits for the demo to say it acted on the one before: the demo
# draws a 32² field in a few milliseconds, so keys sent on a fixed schedule
# can arrive after its last frame.
acted() {  # pattern: seen in the log within 20 s
  for _ in $(seq 200); do
    grep -q "$1" "$log" && return 0
    kill -0 "$pid" 2>/dev/null || return 1
    sleep 0.1
  done
  return 1
}
press() {  # key, what the demo prints when it acts on it ("" when it prints nothing)
  xdotool key "$1"
  if [ -n "$2" ]; then acted "$2" || echo "window_keys: no reaction to $1" >>"$log"; else sleep 0.4; fi
}
press p "demo: paused at tick"
press space "demo: stepped to tick"
press F12 "demo: screenshot"
press r "demo: reloaded scene"
press h ""
press p "demo: running at tick"
wait "$pid"
