#!/usr/bin/env bash
# The three ways users consume mjtether, checked from a fresh clone of the committed tree
# (CI, .ci/run; a few minutes on 2 cores):
#   1. CMake package: build with prefix /usr, `cmake --install --prefix TMP` elsewhere, then an
#      external project (tests/consumer/) with find_package(mjtether) and the examples/ directory
#      copied out of the repository are built against TMP and run; pkg-config compiles too; a
#      parent project with add_subdirectory (tests/consumer/parent/) builds the glue only.
#   2. Debian package: `cpack -G DEB` gives mjtether_<version>_amd64.deb; its file list must
#      equal tests/consumer/deb_contents.txt and its Depends name Debian packages; the CLI from
#      the unpacked package runs.
#   3. Python: the module installed under TMP is imported and runs a short simulation.
#   tools/consumer_check.sh [WORKDIR]   (default: a new temporary directory, removed at the end)
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
work="${1:-}"
if [[ -z "$work" ]]; then
  work="$(mktemp -d)"
  trap 'rm -rf "$work"' EXIT
fi
py=/usr/bin/python3
jobs="$(nproc)"
step() { printf '\n== consumer_check: %s\n' "$*"; }

step "fresh clone of $(git -C "$repo" rev-parse --short HEAD)"
git clone -q "$repo" "$work/src"
cmake -S "$work/src" -B "$work/build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_INSTALL_PREFIX=/usr \
  -DMJTETHER_TESTS=OFF -DMJTETHER_BENCHMARKS=OFF -DMJTETHER_EXAMPLES=OFF \
  ${CMAKE_CXX_COMPILER_LAUNCHER:+-DCMAKE_CXX_COMPILER_LAUNCHER=$CMAKE_CXX_COMPILER_LAUNCHER} \
  >"$work/configure.log"
cmake --build "$work/build" -j"$jobs" >"$work/build.log"

step "1. install into a temporary prefix; find_package consumer, examples, pkg-config"
prefix="$work/prefix"
cmake --install "$work/build" --prefix "$prefix" >"$work/install.log"
cmake -S "$work/src/tests/consumer" -B "$work/consumer" -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$work/consumer" -j"$jobs" >/dev/null
"$work/consumer/consumer"
"$work/consumer/consumer_core"
"$work/consumer/consumer_render"
# The examples directory copied out of the repository builds and runs against the prefix.
cp -r "$work/src/examples" "$work/examples"
cmake -S "$work/examples" -B "$work/examples-build" -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
cmake --build "$work/examples-build" -j"$jobs" >/dev/null
"$work/examples-build/rov_pid" --help | head -1
"$work/examples-build/rov_pid" --duration 8 --bound 0.1 | tail -1
# pkg-config: the relocatable mjtether.pc compiles and links the same program.
pcdir="$(dirname "$(find "$prefix" -name mjtether.pc)")"
libdir="$(dirname "$pcdir")"
g++ -O1 -DMODELS_DIR="\"$prefix/share/mjtether/models\"" "$work/src/tests/consumer/consumer.cc" \
  $(PKG_CONFIG_PATH="$pcdir" pkg-config --cflags --libs mjtether) -Wl,-rpath,"$libdir" \
  -o "$work/consumer_pc"
"$work/consumer_pc" | tail -1
"$prefix/bin/mjtether" --version

step "1b. add_subdirectory from a parent project: engine and glue only, no cache forced"
cmake -S "$work/src/tests/consumer/parent" -B "$work/parent" -DMJTETHER_SOURCE="$work/src" \
  ${CMAKE_CXX_COMPILER_LAUNCHER:+-DCMAKE_CXX_COMPILER_LAUNCHER=$CMAKE_CXX_COMPILER_LAUNCHER} \
  >/dev/null
if [[ -n "$(sed -n 's/^CMAKE_BUILD_TYPE:STRING=//p' "$work/parent/CMakeCache.txt")" ]]; then
  echo "consumer_check: add_subdirectory(mjtether) set the parent's CMAKE_BUILD_TYPE" >&2
  exit 1
fi
cmake --build "$work/parent" -j"$jobs" >/dev/null
"$work/parent/consumer" | tail -1

step "3. Python module from the prefix"
PYTHONPATH="$prefix/lib/python3/dist-packages" "$py" - <<'PY'
import os
import mjtether
print("mjtether", mjtether.__version__, "from", mjtether.__file__)
assert mjtether.__file__.startswith(os.environ["PYTHONPATH"]), mjtether.__file__
sim = mjtether.Simulation(os.path.join(mjtether.models_dir, "bluerov2_heavy.xml"))
sim.step(500)  # 1 s
t = sim.tether("umbilical")
assert t.nodes.shape == (t.segments + 1, 3) and (t.tensions >= 0).all()
print(f"t = {sim.time:.3f} s, ROV at z = {sim.body('rov').pos[2]:.3f} m, "
      f"tension at the ROV {t.reactions['tension_b']:.2f} N")
PY

step "2. Debian package"
(cd "$work/build" && cpack -G DEB >"$work/cpack.log")
version="$(sed -n 's/^project(mjtether VERSION \([0-9.]*\).*/\1/p' "$work/src/CMakeLists.txt")"
deb="$work/build/mjtether_${version}_amd64.deb"
test -f "$deb" || { echo "consumer_check: $deb not built" >&2; exit 1; }
dpkg-deb -c "$deb" | awk '{print $6}' | sed -e 's|^\./|/|' -e 's|/$||' | grep -v '^$' \
  | sed -E 's/cpython-[0-9]+-x86_64-linux-gnu/cpython-XY-x86_64-linux-gnu/' | sort \
  >"$work/deb_contents.txt"
# Expected: the listed files plus every file of the checkout's models/ directory.
{ grep -v '^#' "$work/src/tests/consumer/deb_contents.txt"
  (cd "$work/src" && find models -mindepth 1 | sed 's|^models|/usr/share/mjtether/models|')
} | sort >"$work/deb_expected.txt"
if ! diff -u "$work/deb_expected.txt" "$work/deb_contents.txt"; then
  echo "consumer_check: the .deb's files differ from tests/consumer/deb_contents.txt" >&2
  exit 1
fi
depends="$(dpkg-deb -f "$deb" Depends)"
echo "Depends: $depends"
for p in libmujoco2.2.2 libmujoco-dev libeigen3-dev libosmesa6 python3-numpy; do
  [[ ", $depends," == *", $p"[\ ,]* ]] || { echo "consumer_check: Depends lacks $p" >&2; exit 1; }
done
dpkg-deb -x "$deb" "$work/deb"
"$work/deb/usr/bin/mjtether" --version
"$work/deb/usr/bin/mjtether" info "$work/deb/usr/share/mjtether/models/rov_tether.xml" | head -2
PYTHONPATH="$work/deb/usr/lib/python3/dist-packages" "$py" -c \
  'import mjtether, os; s = mjtether.Simulation(os.path.join(mjtether.models_dir, "rov_tether.xml")); s.step(10); print("deb module:", mjtether.models_dir)'
step "all three consumer paths passed"
