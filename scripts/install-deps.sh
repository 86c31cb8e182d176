#!/usr/bin/env bash
# Installs what one job of scripts/pp5 needs from Debian 12's packages, and nothing more:
#   scripts/install-deps.sh run        build and render, and the Python module (pybind11,
#                                      Python's headers, NumPy and pandas)
#   scripts/install-deps.sh test       + the test suite's tools (Catch2, python3, gtkwave's
#                                      vcd2fst, rsvg-convert, Chromium for the HTML reports'
#                                      browser test, pytest, matplotlib and nbclient with
#                                      ipykernel for the example notebook, and the slurm
#                                      group's packages)
#   scripts/install-deps.sh sanitize   the same as test (gcc's sanitizers come with gcc)
#   scripts/install-deps.sh fuzz       + clang and its fuzzing runtime
#   scripts/install-deps.sh bench      + Google Benchmark
#   scripts/install-deps.sh slurm      + Slurm and munge, for tests/slurm_test.sh (a single-node
#                                      cluster it starts itself; 9 packages, 4 MB). Debian's
#                                      packages enable three system services, munge, slurmctld
#                                      and slurmd (started now and at boot where systemd runs);
#                                      the tests do not use them (this script says so when it
#                                      installs them, and how to turn them off)
#   scripts/install-deps.sh all        everything above
set -euo pipefail
group="${1:-all}"
run=(build-essential cmake ninja-build pkg-config
     libsystemc-dev libglm-dev libfmt-dev nlohmann-json3-dev libcli11-dev libpng-dev zlib1g-dev libassimp-dev
     gemmi-dev tao-pegtl-dev
     pybind11-dev python3-dev python3-numpy python3-pandas)
test=(catch2 python3 gtkwave librsvg2-bin chromium
      python3-pytest python3-matplotlib python3-nbclient python3-nbformat python3-ipykernel)
fuzz=(clang libclang-rt-dev)
bench=(libbenchmark-dev)
slurm=(slurm-wlm munge python3)
case "$group" in
  run) packages=("${run[@]}") ;;
  test|sanitize) packages=("${run[@]}" "${test[@]}" "${slurm[@]}") ;;
  fuzz) packages=("${run[@]}" "${fuzz[@]}") ;;
  bench) packages=("${run[@]}" "${bench[@]}") ;;
  slurm) packages=("${run[@]}" "${slurm[@]}") ;;
  all) packages=("${run[@]}" "${test[@]}" "${fuzz[@]}" "${bench[@]}" "${slurm[@]}") ;;
  *) echo "usage: scripts/install-deps.sh run|test|sanitize|fuzz|bench|slurm|all" >&2; exit 2 ;;
esac
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all packages for '$group' present"
  exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install-deps: installing ${missing[*]}"
$SUDO apt-get update -q
# Through env: sudo resets the environment, which would drop DEBIAN_FRONTEND.
$SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}"
for p in "${missing[@]}"; do
  if [ "$p" = slurm-wlm ] || [ "$p" = munge ]; then
    echo "install-deps: note: Debian's slurm-wlm and munge packages enable the system services" \
         "munge, slurmctld and slurmd (running now and at boot where systemd runs). pp5sim's" \
         "tests do not use them: tests/slurm_test.sh starts its own daemons in a scratch folder." \
         "To turn them off: sudo systemctl disable --now slurmd slurmctld munge"
    break
  fi
done
