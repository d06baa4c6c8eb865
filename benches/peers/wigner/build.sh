#!/usr/bin/env bash
# Builds the Wigner-mirage fan driver against the upstream sources.
#
# The upstream repository has NO license file, so its sources are not copied
# into this repository: this script extracts the needed files at the pinned
# commit into the build directory (default /tmp/wigner-mirage-build, override
# with BUILD_DIR). Upstream source: UPSTREAM_GIT (a local clone or bare git
# dir), else it is cloned from GitHub.
#
# Needs g++ (C++17), libgsl-dev, libeigen3-dev (3.4), libcli11-dev; with
# root and apt-get available, missing packages are installed.
#
# Outputs: $BUILD_DIR/fan        (timing binary, upstream code unmodified)
#          $BUILD_DIR/fan_count  (RHS-counting binary, patched copy of Eikonal.h)
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
BUILD_DIR="${BUILD_DIR:-/tmp/wigner-mirage-build}"
UPSTREAM_URL="https://github.com/balazs-bamer/simple-polynomial-mirage.git"
UPSTREAM_COMMIT="e5c995dfc6a1bc20041460086fc006fca6210e8a"
FILES="RungeKuttaRayBending.h RungeKuttaRayBending.cpp Eikonal.h OdeSolverGsl.h 3dGeomUtil.h mathUtil.h"

need=""
[ -f /usr/include/gsl/gsl_odeiv2.h ] || need="$need libgsl-dev"
[ -f /usr/include/eigen3/Eigen/Dense ] || need="$need libeigen3-dev"
[ -f /usr/include/CLI/CLI.hpp ] || need="$need libcli11-dev"
if [ -n "$need" ]; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
    apt-get install -y $need
  else
    echo "missing packages:$need" >&2; exit 1
  fi
fi

mkdir -p "$BUILD_DIR/upstream" "$BUILD_DIR/upstream_count"
if [ -z "${UPSTREAM_GIT:-}" ]; then
  UPSTREAM_GIT="$BUILD_DIR/upstream.git"
  [ -d "$UPSTREAM_GIT" ] || git clone --bare --quiet "$UPSTREAM_URL" "$UPSTREAM_GIT"
fi
for f in $FILES; do
  git --git-dir="$UPSTREAM_GIT" show "$UPSTREAM_COMMIT:$f" > "$BUILD_DIR/upstream/$f"
  cp "$BUILD_DIR/upstream/$f" "$BUILD_DIR/upstream_count/$f"
done
# Counting copy: increment a global counter at the top of Eikonal::differentials.
sed -i 's/^\(  int differentials(double, const double aY\[\], double aDydt\[\]) const {\)$/\1 ++g_rhs_evals;/' \
  "$BUILD_DIR/upstream_count/Eikonal.h"
grep -q '++g_rhs_evals' "$BUILD_DIR/upstream_count/Eikonal.h" || { echo "RHS-counter patch failed" >&2; exit 1; }
sed -i '1i extern unsigned long long g_rhs_evals;' "$BUILD_DIR/upstream_count/Eikonal.h"

CXXFLAGS="${CXXFLAGS:--O2 -std=c++17}"   # upstream CMakeLists uses -O2 -std=c++17
INC="-I/usr/include/eigen3"
g++ $CXXFLAGS $INC -I"$BUILD_DIR/upstream" "$HERE/fan.cpp" "$BUILD_DIR/upstream/RungeKuttaRayBending.cpp" \
  -o "$BUILD_DIR/fan" -lgsl -lgslcblas -lm
g++ $CXXFLAGS -DCOUNT_RHS $INC -I"$BUILD_DIR/upstream_count" "$HERE/fan.cpp" "$BUILD_DIR/upstream_count/RungeKuttaRayBending.cpp" \
  -o "$BUILD_DIR/fan_count" -lgsl -lgslcblas -lm
echo "built $BUILD_DIR/fan and $BUILD_DIR/fan_count"
