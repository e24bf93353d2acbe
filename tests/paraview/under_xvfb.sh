#!/usr/bin/env bash
# Runs a command in a virtual X server (xvfb-run -a) and prints its output.
# The server runs with -noreset: by default an X server resets when its last client disconnects,
# and ParaView opens the display once to probe OpenGL, closes it and opens it again, so without it
# the second connection can land in the reset and fail ("bad X server connection"). Where that
# message appears all the same, the command runs again, up to three times in all; any other
# outcome is final.
#   under_xvfb.sh XVFB_RUN COMMAND [ARGS...]
set -u
xvfb=$1
shift
for try in 1 2 3; do
  out=$("$xvfb" -a -s "-screen 0 1280x1024x24 -noreset" "$@" 2>&1)
  status=$?
  if ! grep -q "bad X server connection" <<<"$out" || [ "$try" = 3 ]; then
    printf '%s\n' "$out"
    exit "$status"
  fi
  echo "the virtual X server was not there (try $try of 3); running again" >&2
  sleep 2
done
