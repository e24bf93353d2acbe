#!/usr/bin/env bash
# Runs a command in a virtual X server (xvfb-run -a) and prints its output. Where the X server was
# not there when ParaView connected ("bad X server connection": it died or was not yet ready,
# which happens on a loaded machine), runs the command again, up to three times in all; any other
# outcome is final.
#   under_xvfb.sh XVFB_RUN COMMAND [ARGS...]
set -u
xvfb=$1
shift
for try in 1 2 3; do
  out=$("$xvfb" -a "$@" 2>&1)
  status=$?
  if ! grep -q "bad X server connection" <<<"$out" || [ "$try" = 3 ]; then
    printf '%s\n' "$out"
    exit "$status"
  fi
  echo "the virtual X server was not there (try $try of 3); running again" >&2
  sleep 2
done
