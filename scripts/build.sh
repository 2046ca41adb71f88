#!/usr/bin/env bash
# Configures and builds one flavour of dentsim.  Usage: scripts/build.sh release|asan|fuzz [targets...]
#   release: build/release, Release (the default flavour, what the simulator and benchmarks use)
#   asan:    build/asan, -O1 with asserts + AddressSanitizer + UndefinedBehaviorSanitizer (tests)
#   fuzz:    build/fuzz, clang, -O1 + libFuzzer + ASan + UBSan: only reference/, the file readers
#            and the targets in tests/fuzz/ (binaries in build/fuzz/fuzz/; scripts/fuzz.sh runs them)
set -euo pipefail
cd "$(dirname "$0")/.."
flavour=${1:-release}
shift || true
jobs=$(nproc 2>/dev/null || echo 2)
# ccache (when installed) keys on paths relative to the checkout, so clones share the cache.
export CCACHE_BASEDIR="$PWD"
# The compiler's temporary files go under build/ (the disk that holds the build), not to /tmp:
# stop 48's CI run failed with /tmp full ("error writing to /tmp/cc*.s: No space left on device").
mkdir -p build/tmp
export TMPDIR="$PWD/build/tmp"
case "$flavour" in
  release) extra=(-DCMAKE_BUILD_TYPE=Release) ;;
  # -O1 keeps the sanitizer build quick to compile (CI builds both flavours); asserts stay on.
  asan)    extra=(-DCMAKE_BUILD_TYPE=Release "-DCMAKE_CXX_FLAGS_RELEASE=-O1" "-DCMAKE_C_FLAGS_RELEASE=-O1"
                  -DDENTSIM_SANITIZE=ON -DDENTSIM_BUILD_BENCHMARKS=OFF
                  # the Python module, MPI and the install test run in the Release pass only
                  # (an ASan module needs the runtime preloaded into python; OpenMPI leaks by design)
                  -DDENTSIM_PYTHON=OFF -DDENTSIM_MPI=OFF) ;;
  # -g (a crash's stack names file and line) puts the build directory into the debug info, and
  # ccache then keys on it: -fdebug-prefix-map writes it relative, so a checkout at another path
  # (every fresh clone CI makes) gets the cached objects (docs/results/ci_time.md).
  fuzz)    extra=(-DCMAKE_BUILD_TYPE=Release "-DCMAKE_CXX_FLAGS_RELEASE=-O1 -g -fdebug-prefix-map=$PWD=."
                  "-DCMAKE_C_FLAGS_RELEASE=-O1 -g -fdebug-prefix-map=$PWD=."
                  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DDENTSIM_FUZZ=ON
                  -DBUILD_TESTING=OFF -DDENTSIM_BUILD_BENCHMARKS=OFF) ;;
  *) echo "build.sh: unknown flavour '$flavour' (expected release, asan or fuzz)" >&2; exit 2 ;;
esac
mkdir -p build
log="build/$flavour.configure.log"
cmake -S . -B "build/$flavour" "${extra[@]}" > "$log" 2>&1 || { cat "$log" >&2; exit 1; }
if [ $# -gt 0 ]; then
  cmake --build "build/$flavour" -j"$jobs" --target "$@"
else
  cmake --build "build/$flavour" -j"$jobs"
fi
