#!/bin/sh
# The viewer under a real X server (Xvfb), driven by the mouse alone
# (xdotool), keyboard-free: a click on the palette's "steel bar", a click on
# the board, a click on Save. It passes when the saved file holds the bar and
# `alloy check` loads it. Waits are on the X server, the window, the title
# and the file, never on a fixed sleep; one try of each click, no retries: a
# click the viewer loses fails the test, saying which.
#
#   xvfb_mouse_test.sh ALLOY_BINARY
#
# Exit 77 with a message when Xvfb or xdotool is missing. On a failure it
# prints what it waited for, the viewer's and Xvfb's output, the server's
# windows, and keeps the screen as it was (an XWD file, path printed).
#
# Session 20 found the causes of session 19's two failures (docs/kit.md,
# "The viewer under a real X server"): the X server reset itself whenever
# its last client left (here: xdotool), and a viewer connecting then was
# refused and SDL fell back, silently, to a window in memory (now -noreset,
# and the viewer refuses to run with no display); and a press, its release
# and the move to the board reaching the viewer in one frame reached the
# panels as one click on the board (the viewer now gives the panels each
# button change in a frame of its own, Viewer::waits_for_panels).
set -u
alloy=$1
if ! command -v Xvfb >/dev/null 2>&1 || ! command -v xdotool >/dev/null 2>&1; then
  echo "SKIP: Xvfb or xdotool is not installed (apt-get install -y xvfb xdotool)"
  exit 77
fi
dir=$(mktemp -d)
xpid=
vpid=
finish() {
  [ -n "$vpid" ] && kill "$vpid" 2>/dev/null
  [ -n "$xpid" ] && kill "$xpid" 2>/dev/null
  rm -rf "$dir"
}
trap finish EXIT
fail() {
  echo "FAIL: $*"
  [ -f "$dir/viewer.log" ] && sed 's/^/  viewer: /' "$dir/viewer.log"
  [ -s "$dir/xvfb.log" ] && tail -n 20 "$dir/xvfb.log" | sed 's/^/  xvfb: /'
  # What the X server holds: every window's name, and whether the viewer runs.
  if [ -n "${DISPLAY:-}" ]; then
    for w in $(xdotool search --name '.' 2>/dev/null); do
      echo "  window $w: $(xdotool getwindowname "$w" 2>/dev/null)"
    done
  fi
  [ -n "$vpid" ] && { kill -0 "$vpid" 2>/dev/null && echo "  the viewer is running" || echo "  the viewer has exited"; }
  # The screen as the X server holds it (Xvfb -fbdir keeps it as an XWD
  # file): what the viewer had drawn when the test gave up.
  if [ -s "$dir/Xvfb_screen0" ]; then
    shot=$(mktemp "${TMPDIR:-/tmp}/alloy_xvfb_screen.XXXXXX")
    cp "$dir/Xvfb_screen0" "$shot" && echo "  the screen: $shot (XWD)"
  fi
  exit 1
}
# Polls `$@` every 50 ms until it succeeds or `limit` seconds have passed
# since this wait began.
wait_for() {
  waiting_for=$1 limit=$2
  shift 2
  t0=$(date +%s)
  while ! "$@" >/dev/null 2>&1; do
    [ $(($(date +%s) - t0)) -ge "$limit" ] && fail "$waiting_for: not seen within $limit s"
    [ -n "$vpid" ] && ! kill -0 "$vpid" 2>/dev/null && fail "$waiting_for: the viewer exited"
    sleep 0.05
  done
}
start=$(date +%s)
case $alloy in /*) ;; *) alloy=$(pwd)/$alloy ;; esac
# An empty board from a file, so that Save writes without a name to type:
# board.lua (written by hand) -> board_saved.lua beside it, in $dir.
printf 'world { name = "board" }\n' >"$dir/board.lua"

# With no display at all the viewer says so and stops, rather than draw,
# unseen, into SDL's offscreen driver (the "no window" of session 19). Not
# where a GPU device is: there SDL may open a window on the console.
if [ ! -e /dev/dri ]; then
  out=$(env -u DISPLAY -u WAYLAND_DISPLAY -u SDL_VIDEODRIVER "$alloy" view "$dir/board.lua" --frames 1 2>&1) &&
    fail "with no display the viewer ran anyway: $out"
  case $out in
    *"no display answered"*) ;;
    *) fail "with no display the viewer said: $out" ;;
  esac
fi

# A free display number, chosen by the X server itself (-displayfd: it
# writes the number once it listens): two suites started at once both took
# the first display with no lock file (session 19). -noreset: by default
# the server resets itself each time its last client leaves, and a client
# connecting meanwhile is refused; here every xdotool call below is such a
# client, and the viewer, refused, ran with no window (session 20).
Xvfb -displayfd 3 -screen 0 1100x700x24 -nolisten tcp -noreset -fbdir "$dir" \
  3>"$dir/display" >"$dir/xvfb.log" 2>&1 &
xpid=$!
display_written() { [ -s "$dir/display" ]; }
wait_for "the X server choosing a display" 30 display_written
n=$(tr -dc 0-9 <"$dir/display")
export DISPLAY=":$n"
wait_for "the X server on :$n" 30 xdotool getdisplaygeometry

cd "$dir" || fail "cd $dir"
SDL_AUDIODRIVER=dummy SDL_MOUSE_FOCUS_CLICKTHROUGH=1 "$alloy" view "$dir/board.lua" --size 1100x700 >"$dir/viewer.log" 2>&1 &
vpid=$!
# The viewer maps its window once its panels stand still, and the title
# names the file; it ends in " *" while there are edits not saved
# (Viewer::update_title). A loaded machine's start took up to 26 s.
wait_for "the viewer's window" 60 xdotool search --onlyvisible --name 'alloy view - board_saved.lua$'

# The panels' places at 1100 x 700 (docs/images/kit_new_board.png): the
# palette's first button, then a point of the board, then Save. The window
# is at the screen's origin (Xvfb has no window manager).
at() { xdotool getmouselocation | grep -q "^x:$1 y:$2 "; }
click() {
  xdotool mousemove "$1" "$2" || fail "mousemove $1 $2"
  wait_for "the pointer at $1 $2" 10 at "$1" "$2"
  xdotool mousedown 1 || fail "mousedown $1 $2"
  xdotool mouseup 1 || fail "mouseup $1 $2"
}
click 68 456  # Parts: steel bar
click 600 200 # the board: the bar goes there
edited() { xdotool search --onlyvisible --name 'alloy view - board_saved.lua [*]$'; }
wait_for "a steel bar placed (the title's *) after the clicks on the palette and the board" 20 edited
click 150 299 # Save
saved() { grep -q '"steel_bar"' "$dir/board_saved.lua"; }
wait_for "the board saved with the bar after the click on Save" 20 saved
"$alloy" check "$dir/board_saved.lua" >"$dir/check.log" 2>&1 || {
  cat "$dir/check.log"
  fail "alloy check refused the saved board"
}
echo "ok: under Xvfb :$n, three mouse clicks put a steel bar on the board and saved it ($(($(date +%s) - start)) s)"
