#!/usr/bin/env bash
# Debian's Chromium, for scripts/check_report.py (a headless check of outputs/report/index.html).
# Installs nothing when `chromium` is already on the PATH.
set -euo pipefail
command -v chromium >/dev/null && exit 0
sudo=""
[ "$(id -u)" -eq 0 ] || sudo=sudo
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends chromium >/dev/null
chromium --version
