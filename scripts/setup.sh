#!/usr/bin/env bash
# Create .venv and install the project with the versions of scripts/constraints.txt. With --browser also install Debian's Chromium and
# nginx (the browser tests drive the app through scripts/nginx.conf; nginx only runs in
# the foreground on loopback ports there, the package's system service is left alone).
set -euo pipefail
cd "$(dirname "$0")/.."
extras="${EXTRAS:-}"
if [ ! -x .venv/bin/python ]; then
    python3 -m venv .venv
fi
.venv/bin/python -m pip install -q --disable-pip-version-check -U pip
# the exact versions of scripts/constraints.txt (pyproject.toml only gives ranges)
pip_install=(.venv/bin/python -m pip install -q --disable-pip-version-check -c scripts/constraints.txt)
if [ -n "$extras" ]; then
    "${pip_install[@]}" -e ".[$extras]"
else
    "${pip_install[@]}" -e .
fi
# The wheel installs the app folder as `impact_explorer` only; in the checkout, scripts,
# benches and tests import it as `app`, so the checkout's root goes on the venv's path.
site="$(.venv/bin/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')"
printf '%s\n' "$PWD" > "$site/impact_explorer_checkout.pth"
if [ "${1:-}" = "--browser" ]; then
    missing=""
    [ -x /usr/bin/chromium ] || missing="chromium"
    command -v nginx >/dev/null || [ -x /usr/sbin/nginx ] || missing="$missing nginx-light"
    if [ -n "$missing" ]; then
        SUDO=""
        [ "$(id -u)" -eq 0 ] || SUDO="sudo"
        $SUDO apt-get update -qq
        # policy-rc.d 101: the package may not start its system service here
        if [ ! -e /usr/sbin/policy-rc.d ]; then
            printf '#!/bin/sh\nexit 101\n' | $SUDO tee /usr/sbin/policy-rc.d >/dev/null
            $SUDO chmod +x /usr/sbin/policy-rc.d
            trap '$SUDO rm -f /usr/sbin/policy-rc.d' EXIT
        fi
        # shellcheck disable=SC2086
        DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq $missing >/dev/null
    fi
fi
