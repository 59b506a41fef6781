#!/usr/bin/env bash
# Installs what tools/apt-packages.txt lists, and only what is missing: a second run does nothing.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
mapfile -t wanted < <(grep -v '^\s*#' "$here/apt-packages.txt" | sed '/^\s*$/d')

missing=()
for p in "${wanted[@]}"; do
  status="$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)"
  [ "$status" = "install ok installed" ] || missing+=("$p")
done

if [ ${#missing[@]} -gt 0 ]; then
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "setup: not root and no sudo; install: ${missing[*]}" >&2; exit 1; }
    sudo="sudo"
  fi
  echo "setup: installing ${#missing[@]} Debian packages: ${missing[*]}"
  $sudo env DEBIAN_FRONTEND=noninteractive apt-get update -qq
  $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# xacro is not in Debian's ROS: take it from PyPI for ROS's interpreter (scripts/xacro resolves
# $(find) for ROS 1 around it).
if ! /usr/bin/python3 -c 'import xacro' 2>/dev/null; then
  echo "setup: installing xacro 2.1.1 from PyPI"
  sudo=""; [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo /usr/bin/python3 -m pip install -q --break-system-packages --disable-pip-version-check xacro==2.1.1
fi
