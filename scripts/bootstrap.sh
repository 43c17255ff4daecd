#!/usr/bin/env bash
# Idempotent set-up of a fresh machine: Debian toolchain (when root with apt),
# a virtual environment in .venv, and the package with its test extras.
# Used by scripts/main.sh and scripts/test.sh (README "Quick start").
set -euo pipefail
cd "$(dirname "$0")/.."

need_apt=()
PY=${PYTHON:-python3}
# Python itself, its venv module (ensurepip) and its headers (cffi compiles the host builds against Python.h)
command -v "$PY" >/dev/null 2>&1 || need_apt+=(python3)
"$PY" -c 'import ensurepip, venv' >/dev/null 2>&1 || need_apt+=(python3-venv)
"$PY" -c 'import os, sys, sysconfig; sys.exit(not os.path.exists(os.path.join(sysconfig.get_paths()["include"], "Python.h")))' \
  >/dev/null 2>&1 || need_apt+=(python3-dev)
command -v make >/dev/null 2>&1 || need_apt+=(make)
# git: the packaging and docs tests list the tracked files (git ls-files)
command -v git >/dev/null 2>&1 || need_apt+=(git)
command -v arm-none-eabi-gcc >/dev/null 2>&1 || need_apt+=(gcc-arm-none-eabi)
[ -e /usr/lib/arm-none-eabi/newlib/libc.a ] || [ -e /usr/lib/arm-none-eabi/lib/libc.a ] || need_apt+=(libnewlib-arm-none-eabi)
command -v qemu-system-arm >/dev/null 2>&1 || need_apt+=(qemu-system-arm)
command -v openssl >/dev/null 2>&1 || need_apt+=(openssl)  # TLS certificates of the Dask tests
# llvm-mca (Cortex-M7 pipeline model) for the cycle estimate of `mpcgen bench --emulated` (codegen/stages/cycles.py)
command -v llvm-mca >/dev/null 2>&1 || [ -n "$(ls /usr/lib/llvm-*/bin/llvm-mca 2>/dev/null)" ] || need_apt+=(llvm)
command -v gcc >/dev/null 2>&1 || need_apt+=(gcc)
# libFuzzer + sanitizers for the frame decoder's fuzz test (tests/hil/test_fuzz.py): Debian bookworm's clang 14
command -v clang >/dev/null 2>&1 || need_apt+=(clang)
[ -n "$(ls /usr/lib/llvm-*/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a 2>/dev/null)" ] || need_apt+=(libclang-rt-14-dev)
# headless Chromium: the evidence page's test renders it (tests/stages/test_evidence.py: --dump-dom, --screenshot)
command -v chromium >/dev/null 2>&1 || need_apt+=(chromium)
if [ ${#need_apt[@]} -gt 0 ]; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "bootstrap: apt-get install ${need_apt[*]}" >&2
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${need_apt[@]}" >/dev/null
  else
    echo "bootstrap: missing ${need_apt[*]} (install with: sudo apt-get install ${need_apt[*]}); the tests that need them will fail" >&2
  fi
fi

if [ ! -x .venv/bin/python ]; then
  echo "bootstrap: creating .venv" >&2
  "$PY" -m venv .venv
fi
stamp=.venv/.mpcgen-installed
# A regular (not editable) install: setuptools warns about every editable mode.  Reinstalled
# whenever a file of the package is newer than the last install, so .venv/bin/mpcgen is current.
if [ ! -f "$stamp" ] || [ -n "$(find pyproject.toml codegen templates firmware hil -newer "$stamp" -print -quit)" ]; then
  echo "bootstrap: pip install .[test]" >&2
  .venv/bin/python -m pip install -q --upgrade pip "setuptools>=68" wheel
  .venv/bin/python -m pip install -q ".[test]"
  touch "$stamp"
fi
