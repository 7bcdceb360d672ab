#!/usr/bin/env bash
# One entry point for a fresh Debian machine (run as root):
#   bash scripts/bootstrap.sh demo   install what is missing, build, grow + render the demo scene
#   bash scripts/bootstrap.sh test   install what is missing, build, run the whole test suite
#                                    (Release build: all labels; sanitizer build: the `hard` label;
#                                    30 s of fuzzing per parser; the clang-format check)
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(cmake g++ make libeigen3-dev libsuitesparse-dev libarpack2-dev libboost-graph-dev
          catch2 libtomlplusplus-dev libcli11-dev nlohmann-json3-dev python3-matplotlib librsvg2-bin
          pybind11-dev python3-dev python3-numpy python3-pandas python3-gsd python3-pytest python3-ase
          python3-meshio help2man slurm-wlm munge clang-14 libclang-rt-14-dev clang-format-14)

install_missing() {
  local missing=()
  for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if ((${#missing[@]})); then
    echo "bootstrap: installing ${missing[*]}" >&2
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  fi
}

build() {  # build DIR [cmake options...]
  local dir=$1; shift
  cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
  cmake --build "$dir" -j"$(nproc)"
}

# budjam, its man page and completion, the libraries and `import budjam` under /usr/local.
install_build() { cmake --install build >/dev/null; }

case "${1:-}" in
  demo)
    install_missing
    build build
    install_build
    rm -rf runs/demo
    ./build/budjam grow data/scenes/demo.toml --out runs/demo
    ./build/budjam render runs/demo/packings/jammed.pack -o runs/demo/jammed.svg --png
    echo "bootstrap: demo run in runs/demo (summary.json, logs, packings, jammed.svg/.png)"
    ;;
  test)
    install_missing
    build build
    install_build
    (cd build && ctest --output-on-failure -j"$(nproc)")
    # Hard cases again under AddressSanitizer + UndefinedBehaviorSanitizer.
    build build-sanitize -DBUDJAM_SANITIZE=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo
    (cd build-sanitize && ctest --output-on-failure -j"$(nproc)" -L hard)
    # The parsers of scenes, packings and checkpoints under libFuzzer, 30 s each (docs/files.md).
    bash scripts/fuzz.sh 30
    bash scripts/check_format.sh
    ;;
  *)
    echo "usage: bash scripts/bootstrap.sh demo|test" >&2
    exit 2
    ;;
esac
