#!/usr/bin/env bash
# Set up (if needed) and serve the Impact Explorer on http://localhost:${PORT:-5006}/app
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
# compile the Numba kernels into their cache now, not on the first visitor's page
.venv/bin/python -c "import impactlib; impactlib.warmup()"
exec .venv/bin/panel serve app/app.py --port "${PORT:-5006}" \
    --allow-websocket-origin "${IMPACT_ALLOWED_ORIGINS:-localhost:${PORT:-5006}}" "$@"
