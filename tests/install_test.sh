#!/usr/bin/env bash
# Installs the built project into a scratch prefix and builds and runs a program against it with
# find_package(exabricks).
set -euo pipefail
build=${1:?usage: install_test.sh BUILD_DIR SOURCE_DIR TMPDIR [LINK_FLAGS] [CXX]}
source=${2:?}
dir=${3:?}
link_flags=${4:-} # a sanitizer build's library needs its runtime in the consumer too
cxx=${5:-c++}      # the project's compiler (a sanitizer's runtime is the compiler's own)
rm -rf "$dir" && mkdir -p "$dir"
cmake --install "$build" --prefix "$dir/prefix" > "$dir/install.log"
test -f "$dir/prefix/include/exabricks/render/renderer.h"
test -x "$dir/prefix/bin/exabricks"
cmake -S "$source/tests/consumer" -B "$dir/consumer" -DCMAKE_PREFIX_PATH="$dir/prefix" \
  -DCMAKE_EXE_LINKER_FLAGS="$link_flags" -DCMAKE_CXX_COMPILER="$cxx" > "$dir/configure.log"
cmake --build "$dir/consumer" > "$dir/build.log"
"$dir/consumer/consumer"
