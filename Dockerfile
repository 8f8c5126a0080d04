# Impact Explorer: serves the Panel app at http://HOST:5006/app (health: /liveness).
#
#   docker build -t impact-explorer .
#   docker run --rm -p 127.0.0.1:5006:5006 impact-explorer
#   docker run --rm -p 8080:5006 -e IMPACT_ALLOWED_ORIGINS=example.org,example.org:8080 impact-explorer
#
#   docker run --rm -p 127.0.0.1:5006:5006 -e IMPACT_PROCS=2 impact-explorer
#
# IMPACT_ALLOWED_ORIGINS: comma-separated host[:port] origins allowed to open the app's
# websocket (default localhost:5006). "*" or an empty value is refused at start. Behind
# a reverse proxy these are the names the browsers use (the proxy's), not the container's.
# IMPACT_PROCS: server processes (panel serve --num-procs, default 1), each with its own
# sessions and caches; give the container that many CPUs. Anything but a whole number
# >= 1 is refused at start (0 would let Tornado take the host's core count).
# IMPACT_DASK_SCHEDULER: a Dask scheduler (tcp://host:8786) whose workers compute the
# regime maps, basins and boundary curves (same results; the workers need impactlib and
# the dask versions of scripts/constraints.txt); empty (the default): the server's threads.
#   docker run --rm -p 127.0.0.1:5006:5006 -e IMPACT_DASK_SCHEDULER=tcp://10.0.0.5:8786 impact-explorer
# The process runs as uid 10001 and writes only to /var/cache/impact (its HOME, the
# Numba cache warmed at build time and TMPDIR), so the image also
# runs with a read-only root: --read-only -v impact-cache:/var/cache/impact.
# scripts/container_check.sh builds and checks this image with podman.
FROM debian:bookworm-slim

ENV VIRTUAL_ENV=/opt/venv \
    IMPACT_HOME=/opt/impact \
    IMPACT_CACHE=/var/cache/impact \
    PYTHONUNBUFFERED=1
# NUMBA_CPU_NAME=generic makes the cache warmed here valid on any x86-64 host, not just
# on a CPU like the build machine's (otherwise Numba recompiles at the first request).
ENV PATH="${VIRTUAL_ENV}/bin:${PATH}" \
    NUMBA_CACHE_DIR="${IMPACT_CACHE}/numba" \
    NUMBA_CPU_NAME=generic \
    IMPACT_ALLOWED_ORIGINS=localhost:5006 \
    IMPACT_DASK_SCHEDULER="" \
    IMPACT_PROCS=1

# Debian's own Python 3.11 (python3 3.11.2-1+b1 is bookworm's for its whole life; the
# interpreter under it takes Debian's security updates). ca-certificates is left to track
# Debian's updates on purpose: a trust store pinned to an old version is a liability.
# hadolint ignore=DL3008
RUN apt-get update \
    && apt-get install -y --no-install-recommends \
        python3=3.11.2-1+b1 python3-venv=3.11.2-1+b1 ca-certificates \
    && rm -rf /var/lib/apt/lists/*

RUN groupadd --gid 10001 app \
    && useradd --no-log-init --no-create-home --uid 10001 --gid app \
        --home-dir "${IMPACT_CACHE}" --shell /usr/sbin/nologin app \
    && install -d -o app -g app -m 0750 "${IMPACT_CACHE}" "${NUMBA_CACHE_DIR}" \
        "${IMPACT_CACHE}/tmp"

# Install the project (not editable, with the dask extra for IMPACT_DASK_SCHEDULER) with the
# versions pinned in scripts/constraints.txt, using
# the pip that Debian's python3-venv ships (23.0.1, which uses Debian's CA store).
# RUN steps name paths only through ENV/ARG variables: tests/container replays them.
ARG IMPACT_SRC=/tmp/impact-src
COPY pyproject.toml README.md scripts/constraints.txt ${IMPACT_SRC}/
COPY impactlib/ ${IMPACT_SRC}/impactlib/
COPY app/ ${IMPACT_SRC}/app/
RUN python3 -m venv "${VIRTUAL_ENV}" \
    && "${VIRTUAL_ENV}/bin/pip" install --no-cache-dir --disable-pip-version-check \
        -c "${IMPACT_SRC}/constraints.txt" "${IMPACT_SRC}[dask]" \
    && rm -rf "${IMPACT_SRC}"

COPY app/ ${IMPACT_HOME}/app/
WORKDIR ${IMPACT_HOME}

USER 10001:10001
ENV TMPDIR="${IMPACT_CACHE}/tmp" \
    PYTHONDONTWRITEBYTECODE=1
# Warm Numba's cache as the user that serves, into the only writable directory, with
# impactlib.warmup() if the core has one, else every kernel the app's pages and the
# accuracy readout run (tests/container checks a first page compiles nothing new);
# fail the build if nothing was cached. -P keeps the working directory off sys.path.
RUN python -P -c "import impactlib as il; w = getattr(il, 'warmup', None); w and w(); p = il.Params(m=1, c=0.05, k=1, g=0, r=0.8, omega=2.0); il.classify(il.simulate(p)); il.simulate(p, dense=200); il.simulate(p, method='rk4', dt=0.01, t_end=20, t_record=10); il.simulate(p, method='rk45', t_end=20, t_record=10); il.bifurcation(p, 'omega', [1.0, 2.0], t_end=20, t_record=10)" \
    && test -n "$(find "${NUMBA_CACHE_DIR}" -name '*.nbi' -print -quit)"

EXPOSE 5006
HEALTHCHECK --interval=30s --timeout=5s --start-period=60s --retries=3 \
    CMD ["python", "-c", "import urllib.request; urllib.request.urlopen('http://127.0.0.1:5006/liveness', timeout=4)"]

# No --admin, no --autoreload, no --dev. Each origin in IMPACT_ALLOWED_ORIGINS becomes one
# --allow-websocket-origin; a "*" anywhere or an empty list stops the start with code 64,
# and so does an IMPACT_PROCS that is not a whole number >= 1.
CMD ["/bin/sh", "-c", "case \"${IMPACT_ALLOWED_ORIGINS}\" in ''|*'*'*) echo 'IMPACT_ALLOWED_ORIGINS must list host[:port] origins; empty or * is refused' >&2; exit 64;; esac; case \"${IMPACT_PROCS}\" in ''|*[!0-9]*|0*) echo 'IMPACT_PROCS must be a whole number of server processes, 1 or more' >&2; exit 64;; esac; set -f; IFS=','; set --; for o in ${IMPACT_ALLOWED_ORIGINS}; do set -- \"$@\" --allow-websocket-origin \"$o\"; done; exec panel serve app/app.py --address 0.0.0.0 --num-procs \"${IMPACT_PROCS}\" --port 5006 --liveness \"$@\""]
