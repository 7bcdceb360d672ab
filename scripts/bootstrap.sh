#!/usr/bin/env bash
# One entry point for a fresh Debian machine (run as root):
#   bash scripts/bootstrap.sh demo   install what is missing, build, grow + render the demo scene
#   bash scripts/bootstrap.sh test   install what is missing, build, run the whole test suite
#                                    (Release build: all labels; sanitizer build: the `hard` label;
#                                    30 s of fuzzing per parser; the clang-format check)
set -euo pipefail
cd "$(dirname "$0")/.."

# What the demo needs: the compilers, the libraries, the Python module's build and runtime.
# OpenBLAS becomes the system's libblas.so.3: CHOLMOD's supernodal factors and ARPACK run on its
# kernels (held on one thread, docs/speed.md "BLAS and OpenMP"), 1.7x less CPU than the reference BLAS's.
demo_packages=(cmake g++ make libeigen3-dev libsuitesparse-dev libarpack2-dev libboost-graph-dev
               libopenblas0-openmp libtomlplusplus-dev libcli11-dev nlohmann-json3-dev librsvg2-bin
               pybind11-dev python3-dev python3-numpy python3-pandas help2man bash-completion)
# What the whole test suite needs on top: Catch2, the independent readers of every file format,
# `pip install .` into a venv, the notebook, Slurm, the sanitizer and fuzzing compilers, clang-format.
test_packages=(catch2 python3-matplotlib python3-gsd python3-pytest python3-ase python3-meshio
               python3-venv python3-pip python3-setuptools python3-wheel jupyter-notebook python3-nbconvert
               python3-ipykernel slurm-wlm munge clang-14 libclang-rt-14-dev clang-format-14)
# The demo builds budjam and the Python module only; `test` builds everything (tests, benchmarks).
# Both compile the libraries and budjam in unity batches (half the CPU time); the sanitizer build
# of `test` compiles every source alone, so CI checks that each stands on its own as well.
demo_options=(-DBUILD_TESTING=OFF -DBUDJAM_BENCHMARKS=OFF -DBUDJAM_UNITY_BUILD=ON)
test_options=(-DBUILD_TESTING=ON -DBUDJAM_BENCHMARKS=ON -DBUDJAM_UNITY_BUILD=ON)

install_missing() {  # install_missing PACKAGE...
  local missing=()
  for p in "$@"; do
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
    echo "bootstrap: demo set-up: the missing packages, then budjam and the Python module:" \
      "about 4 CPU-minutes of compiling (about 2 min on 2 idle cores, longer on a busy machine; README)" >&2
    install_missing "${demo_packages[@]}"
    build build "${demo_options[@]}"
    install_build
    bash scripts/demo_run.sh ./build/budjam runs/demo
    echo "bootstrap: demo run in runs/demo (summary.json, logs, packings, packings/jammed.svg/.png)"
    ;;
  test)
    install_missing "${demo_packages[@]}" "${test_packages[@]}"
    build build "${test_options[@]}"
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
