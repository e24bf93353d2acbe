#!/usr/bin/env bash
# Installs the built project into a scratch prefix and builds and runs a program against it with
# find_package(exabricks).
set -euo pipefail
build=${1:?usage: install_test.sh BUILD_DIR SOURCE_DIR TMPDIR}
source=${2:?}
dir=${3:?}
rm -rf "$dir" && mkdir -p "$dir"
cmake --install "$build" --prefix "$dir/prefix" > "$dir/install.log"
test -f "$dir/prefix/include/exabricks/render/renderer.h"
test -x "$dir/prefix/bin/exabricks"
cmake -S "$source/tests/consumer" -B "$dir/consumer" -DCMAKE_PREFIX_PATH="$dir/prefix" > "$dir/configure.log"
cmake --build "$dir/consumer" > "$dir/build.log"
"$dir/consumer/consumer"
