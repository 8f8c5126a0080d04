#!/usr/bin/env bash
# Set up (if needed, including Debian's Chromium and nginx) and run the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
EXTRAS=test,dask bash scripts/setup.sh --browser
exec .venv/bin/python -m pytest "$@"
