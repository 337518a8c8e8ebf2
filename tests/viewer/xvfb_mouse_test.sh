#!/bin/sh
# The viewer under a real X server (Xvfb), driven by the mouse alone
# (xdotool), keyboard-free: a click on the palette's "steel bar", a click on
# the board, a click on Save. It passes when the saved file holds the bar and
# `alloy check` loads it. Waits are on the X server, the window and the file,
# never on a fixed sleep; each attempt gives up after 45 s (a loaded machine's passing run takes 1 to 26 s).
#
#   xvfb_mouse_test.sh ALLOY_BINARY
#
# Exit 77 with a message when Xvfb or xdotool is missing.
#
# Session 14 lost most clicks on the ImGui panels here: the X server hands
# the pointer's move and the press to the viewer together, and Dear ImGui
# gives a click to a window only if the pointer hovered it in the frame
# before. The viewer now holds such a press back for one frame
# (Viewer::frame), and the clicks below arrive. ctest runs this script
# (label xvfb); docs/kit.md, "The viewer under a real X server".
set -u
alloy=$1
if ! command -v Xvfb >/dev/null 2>&1 || ! command -v xdotool >/dev/null 2>&1; then
  echo "SKIP: Xvfb or xdotool is not installed (apt-get install -y xvfb xdotool)"
  exit 77
fi
# Up to five attempts, each with its own X server and viewer. On the
# development machine, loaded by several builds, about one run in ten failed
# in one of two ways that did not repeat in the next run (session 19: the
# window never appeared within 90 s, no window at all on the server; or five
# placements in a row were not seen while the window was there) and that an
# idle machine did not reproduce in 20 runs. Later that session both came
# in about one run in three on the idle machine, run alone: not found, open
# (docs/kit.md). A broken viewer fails every attempt; each failed attempt's
# output is printed.
if [ -z "${ALLOY_XVFB_ATTEMPT:-}" ]; then
  for attempt in 1 2 3 4 5; do
    out=$(ALLOY_XVFB_ATTEMPT=$attempt sh "$0" "$@" 2>&1)
    rc=$?
    printf '%s\n' "$out" | sed "s/^/[attempt $attempt] /"
    [ $rc -eq 0 ] || [ $rc -eq 77 ] && exit $rc
  done
  echo "FAIL: five attempts failed"
  exit 1
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
  # What the X server holds, for a failure that does not repeat (session 18:
  # one run of CI's ctest timed out waiting for the window, then 11 in a row
  # passed in 1.5 to 4.5 s): every window's name, and whether the viewer runs.
  if [ -n "${DISPLAY:-}" ]; then
    for w in $(xdotool search --name '.' 2>/dev/null); do
      echo "  window $w: $(xdotool getwindowname "$w" 2>/dev/null)"
    done
  fi
  [ -n "$vpid" ] && { kill -0 "$vpid" 2>/dev/null && echo "  the viewer is running" || echo "  the viewer has exited"; }
  exit 1
}
# Polls `$@` every 50 ms until it succeeds or `deadline` (seconds since the
# start) passes.
start=$(date +%s)
wait_for() {
  waiting_for=$1
  shift
  while ! "$@" >/dev/null 2>&1; do
    [ $(($(date +%s) - start)) -ge 45 ] && fail "timed out waiting for $waiting_for"
    sleep 0.05
  done
}

# A free display number, chosen by the X server itself (-displayfd: it
# writes the number once it listens). Choosing "the first with no lock file"
# here raced with another copy of this test started at the same moment (two
# build folders' suites, session 19): both took :90, the second Xvfb failed,
# both viewers opened on the first server, and when the first test ended it
# took the second's display with it (a 90 s timeout waiting for the window).
Xvfb -displayfd 3 -screen 0 1100x700x24 -nolisten tcp 3>"$dir/display" >"$dir/xvfb.log" 2>&1 &
xpid=$!
display_written() { [ -s "$dir/display" ]; }
wait_for "the X server to choose a display" display_written
n=$(tr -dc 0-9 <"$dir/display")
export DISPLAY=":$n"
wait_for "the X server on :$n" xdotool getdisplaygeometry

# An empty board from a file, so that Save writes without a name to type:
# board.lua (written by hand) -> board_saved.lua beside it, in $dir.
printf 'world { name = "board" }\n' >"$dir/board.lua"
case $alloy in /*) ;; *) alloy=$(pwd)/$alloy ;; esac
cd "$dir" || fail "cd $dir"
SDL_AUDIODRIVER=dummy SDL_MOUSE_FOCUS_CLICKTHROUGH=1 "$alloy" view "$dir/board.lua" --size 1100x700 >"$dir/viewer.log" 2>&1 &
vpid=$!
# The title names the file once the board is loaded and drawn, and ends in
# " *" while there are edits not saved (Viewer::update_title).
wait_for "the viewer's window" xdotool search --onlyvisible --name 'alloy view - board_saved.lua$'
win=$(xdotool search --onlyvisible --name 'alloy view' | head -n 1)

# The panels' places at 1100 x 700 (docs/images/kit_new_board.png): the
# palette's first button, then a point of the board, then Save. Each step
# is checked by what it changes (the title's " *", then the file) and
# tried again if the window missed it (at most 5 times): the viewer reads
# the mouse between frames, and a press and release inside one frame can
# reach a panel button as no click at all.
at() { xdotool getmouselocation | grep -q "^x:$1 y:$2 "; }
click() {
  # The window is at the screen's origin (Xvfb has no window manager); the
  # button goes down once the X server has the pointer there.
  xdotool mousemove "$1" "$2" || fail "mousemove $1 $2"
  wait_for "the pointer at $1 $2" at "$1" "$2"
  xdotool mousedown 1 || fail "mousedown $1 $2"
  xdotool mouseup 1 || fail "mouseup $1 $2"
}
# Tries `step` until `check` holds, each time waiting up to 2 s for it.
attempt() {
  what=$1 step=$2 check=$3
  tries=0
  while :; do
    $step
    t0=$(date +%s)
    while [ $(($(date +%s) - t0)) -lt 2 ]; do
      $check && return 0
      sleep 0.05
    done
    tries=$((tries + 1))
    [ $tries -ge 5 ] && fail "$what: not seen after 5 tries"
    echo "retry: $what"
  done
}
place() {
  click 68 456   # Parts: steel bar
  click 600 200  # the board: the bar goes there
}
edited() { xdotool search --onlyvisible --name 'alloy view - board_saved.lua [*]$' >/dev/null 2>&1; }
save() { click 150 299; }
saved() { grep -q '"steel_bar"' "$dir/board_saved.lua" 2>/dev/null; }
attempt "a steel bar placed (the title's *)" place edited
attempt "the board saved with the bar" save saved
"$alloy" check "$dir/board_saved.lua" >"$dir/check.log" 2>&1 || {
  cat "$dir/check.log"
  fail "alloy check refused the saved board"
}
echo "ok: under Xvfb :$n, three mouse clicks put a steel bar on the board and saved it ($(($(date +%s) - start)) s)"
