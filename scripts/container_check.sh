#!/usr/bin/env bash
# Build the real image from ./Dockerfile with podman and check that it serves.
#
#   sudo bash scripts/container_check.sh        (Debian/Ubuntu host; about 4-6 min cold)
#
# There is no Docker engine or registry here, so the base image named in FROM is made
# from Debian's own packages (debootstrap minbase bookworm, upgraded, with
# ca-certificates) and tagged with that name; the Dockerfile's apt step then installs
# python3 and python3-venv into it as it would into debian:bookworm-slim.
# Checks: the build passes (HEALTHCHECK kept: docker format); /liveness, /app and
# /liveness?endpoint=/app answer 200; the health check reports healthy; every process
# runs as uid 10001; the server's user can write only under /var/cache/impact (and the
# kernel's world-writable /tmp, /var/tmp, /dev/shm, which the read-only run removes);
# a websocket from a foreign origin gets 403; IMPACT_ALLOWED_ORIGINS='*' is refused;
# the image serves with a read-only root, all capabilities dropped and only a volume
# on the cache dir. Containers, the volume and the built image are removed at the end
# (KEEP_IMAGE=1 keeps the image; the stand-in base is kept, CLEAN_BASE=1 removes it).
#
# Env: PORT (host loopback port, default 15006), IMAGE (default localhost/impact-explorer:check).
# Exit: 0 all checks passed, 1 a check failed, 2 not root, 77 podman unavailable.
set -euo pipefail
cd "$(dirname "$0")/.."

PORT="${PORT:-15006}"
IMAGE="${IMAGE:-localhost/impact-explorer:check}"
NAME="impact-check-$$"
HARD="impact-check-ro-$$"
VOLUME="impact-check-cache-$$"
CA=/etc/ssl/certs/ca-certificates.crt
WORK="$(mktemp -d /tmp/impact-container-check.XXXXXX)"
T0=$(date +%s)
FAILED=0
RESULTS=()

say() { printf '[%4ss] %s\n' "$(($(date +%s) - T0))" "$*"; }
check() { # check NAME COMMAND...: run a check, record PASS/FAIL
    local name="$1"; shift
    if "$@" >"$WORK/check.out" 2>&1; then
        RESULTS+=("PASS  $name"); say "PASS  $name"
    else
        RESULTS+=("FAIL  $name"); say "FAIL  $name"; sed 's/^/      /' "$WORK/check.out" | tail -20
        FAILED=1
    fi
}
cleanup() {
    set +e
    podman rm -f -t 5 "$NAME" "$HARD" >/dev/null 2>&1
    podman volume rm -f "$VOLUME" >/dev/null 2>&1
    [ "${KEEP_IMAGE:-0}" = 1 ] || podman rmi -f "$IMAGE" >/dev/null 2>&1
    if [ "${CLEAN_BASE:-0}" = 1 ] && [ -n "${BASE:-}" ]; then
        podman rmi -f "$BASE" "docker.io/library/$BASE" >/dev/null 2>&1
    fi
    rm -rf "$WORK"
}
trap cleanup EXIT

if [ "$(id -u)" -ne 0 ]; then
    echo "container_check: run as root (rootful podman, debootstrap)" >&2; exit 2
fi
if ! command -v podman >/dev/null || ! command -v debootstrap >/dev/null || ! command -v runc >/dev/null; then
    say "installing podman buildah runc debootstrap"
    if ! { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
            podman buildah runc debootstrap >"$WORK/apt.log" 2>&1; }; then
        tail -20 "$WORK/apt.log" >&2; echo "container_check: podman unavailable" >&2; exit 77
    fi
fi
say "$(podman --version), $(runc --version | head -1)"

# ---- the stand-in base image ------------------------------------------------------
BASE="$(awk 'toupper($1) == "FROM" { print $2; exit }' Dockerfile)"
if podman image exists "docker.io/library/$BASE"; then
    say "base $BASE: stand-in already present"
else
    SOURCES=/etc/apt/sources.list.d/debian.sources
    MIRROR="$(awk '/^URIs:/ { print $2; exit }' "$SOURCES" 2>/dev/null || true)"
    MIRROR="${MIRROR:-http://deb.debian.org/debian}"
    say "base $BASE: debootstrap minbase bookworm from $MIRROR"
    ROOTFS="$WORK/rootfs"
    debootstrap --variant=minbase --include=ca-certificates bookworm "$ROOTFS" "$MIRROR" \
        >"$WORK/debootstrap.log" 2>&1 || { tail -30 "$WORK/debootstrap.log"; exit 1; }
    # Same sources as the official image (bookworm, -updates, -security), then upgrade.
    if [ -f "$SOURCES" ]; then
        rm -f "$ROOTFS/etc/apt/sources.list"
        cp "$SOURCES" "$ROOTFS/etc/apt/sources.list.d/debian.sources"
    fi
    chroot "$ROOTFS" /bin/sh -c 'apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get -y -qq upgrade && apt-get clean && rm -rf /var/lib/apt/lists/*' \
        >"$WORK/upgrade.log" 2>&1 || { tail -30 "$WORK/upgrade.log"; exit 1; }
    tar -C "$ROOTFS" -c . | podman import \
        --change 'ENV PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin' \
        --change 'CMD ["bash"]' - "docker.io/library/$BASE" >"$WORK/import.log" 2>&1 \
        || { cat "$WORK/import.log"; exit 1; }
    rm -rf "$ROOTFS"
    say "base $BASE: imported"
fi

# ---- build -------------------------------------------------------------------------
say "building $IMAGE"
B0=$(date +%s)
# Layers are cached only when the image is kept (KEEP_IMAGE=1); else nothing is left behind.
LAYERS=false; [ "${KEEP_IMAGE:-0}" = 1 ] && LAYERS=true
if ! podman build --pull=never --isolation chroot --network host --format docker \
        --layers="$LAYERS" --force-rm -v "$CA:$CA:ro" -t "$IMAGE" . >"$WORK/build.log" 2>&1; then
    tail -40 "$WORK/build.log"; say "FAIL  build"; exit 1
fi
say "PASS  build ($(($(date +%s) - B0)) s); image $(podman image inspect --format '{{.Size}}' "$IMAGE" | awk '{printf "%.0f MB", $1/1e6}')"
RESULTS+=("PASS  build")

# ---- helpers -----------------------------------------------------------------------
http_ok() { # http_ok URL [TIMEOUT]
    python3 - "$1" "${2:-60}" <<'EOF'
import sys, urllib.request
with urllib.request.urlopen(sys.argv[1], timeout=float(sys.argv[2])) as r:
    body = r.read()
    print(r.status, len(body), "bytes")
    sys.exit(0 if r.status == 200 else 1)
EOF
}
wait_live() { # wait_live CONTAINER
    local i
    for i in $(seq 1 180); do
        if python3 -c "import urllib.request,sys; urllib.request.urlopen(sys.argv[1], timeout=3)" \
                "http://127.0.0.1:$PORT/liveness" 2>/dev/null; then
            say "$1 live after ~${i}s"; return 0
        fi
        if [ "$(podman inspect --format '{{.State.Running}}' "$1")" != true ]; then
            podman logs "$1" | tail -30; return 1
        fi
        sleep 1
    done
    podman logs "$1" | tail -30; return 1
}
ws_origin() { # ws_origin ORIGIN -> HTTP status of a websocket upgrade on /app/ws (as a page sends it)
    python3 - "$PORT" "$1" <<'EOF'
import base64, json, os, socket, sys, time
port, origin = int(sys.argv[1]), sys.argv[2]
payload = {"session_id": base64.urlsafe_b64encode(os.urandom(33)).decode(),
           "session_expiry": int(time.time()) + 300}
token = base64.urlsafe_b64encode(json.dumps(payload).encode()).decode().rstrip("=")
key = base64.b64encode(os.urandom(16)).decode()
req = (f"GET /app/ws HTTP/1.1\r\nHost: localhost:{port}\r\nUpgrade: websocket\r\n"
       f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n"
       f"Sec-WebSocket-Protocol: bokeh, {token}\r\nOrigin: {origin}\r\n\r\n")
with socket.create_connection(("127.0.0.1", port), timeout=30) as s:
    s.sendall(req.encode())
    status = s.recv(4096).split(b"\r\n", 1)[0].split()[1].decode()
    if status == "101":
        time.sleep(2)
        s.sendall(b"\x88\x80" + os.urandom(4))  # masked close frame
        time.sleep(0.5)
    print(status)
EOF
}
only_cache_writable() { # CONTAINER [strict]: the serving user may write under /var/cache/impact only
    podman exec -i -e STRICT="${2:-}" "$1" python -P - <<'EOF'
import json, os, sys
dirs = ["/", "/opt", "/opt/venv", "/opt/venv/bin", "/opt/venv/lib/python3.11/site-packages",
        "/opt/venv/lib/python3.11/site-packages/impactlib", "/opt/impact", "/opt/impact/app",
        "/etc", "/usr", "/usr/local", "/var", "/var/cache", "/var/lib", "/var/log", "/home",
        "/root", "/run", "/srv", "/mnt", "/tmp", "/var/tmp", "/dev/shm",
        "/var/cache/impact", "/var/cache/impact/numba", "/var/cache/impact/tmp"]
allowed = ("/var/cache/impact",)
strict = os.environ.get("STRICT") == "strict"
# A container always has a tmpfs /dev/shm; /tmp and /var/tmp go with --read-only.
kernel_tmp = ("/dev/shm",) if strict else ("/tmp", "/var/tmp", "/dev/shm")
writable = []
for d in dirs:
    try:
        p = os.path.join(d, f".write-probe-{os.getpid()}")
        with open(p, "w") as f:
            f.write("x")
        os.remove(p)
        writable.append(d)
    except OSError:
        pass
bad = [d for d in writable if not d.startswith(allowed) and d not in kernel_tmp]
print("uid", os.getuid(), "writable:", writable, "forbidden:", bad)
sys.exit(1 if bad or "/var/cache/impact/numba" not in writable else 0)
EOF
}
ws_refused() { local s; s="$(ws_origin "$1")"; echo "status $s"; [ "$s" = 403 ]; }
ws_admitted() { local s; s="$(ws_origin "$1")"; echo "status $s"; [ "$s" = 101 ]; }
no_root_process() { # CONTAINER: every process in the container runs as uid 10001
    podman exec "$1" python -P -c '
import glob, sys
uids = {}
for f in glob.glob("/proc/[0-9]*/status"):
    try:
        lines = open(f).read().splitlines()
    except OSError:
        continue
    name = next(l.split()[1] for l in lines if l.startswith("Name:"))
    uid = next(l.split()[1:] for l in lines if l.startswith("Uid:"))
    uids[f.split("/")[2] + ":" + name] = uid
print(uids)
sys.exit(0 if uids and all(set(u) == {"10001"} for u in uids.values()) else 1)'
}
healthcheck_in_image() {
    podman image inspect "$IMAGE" | python3 -c '
import json, sys
d = json.load(sys.stdin)[0]
hc = d.get("Healthcheck") or d.get("HealthCheck") or d.get("Config", {}).get("Healthcheck")
print(hc)
sys.exit(0 if hc and "liveness" in json.dumps(hc) else 1)'
}
no_traceback() { # CONTAINER
    podman logs "$1" >"$WORK/logs.txt" 2>&1
    tail -5 "$WORK/logs.txt"
    ! grep -E 'Traceback|^ERROR' "$WORK/logs.txt"
}

# ---- run: defaults -----------------------------------------------------------------
say "run $NAME on 127.0.0.1:$PORT"
# --health-interval disable: no systemd here for podman's timer; `healthcheck run` still works.
podman --runtime runc run -d --name "$NAME" --pull never --health-interval disable \
    --ulimit nofile=1024:1024 --ulimit nproc=1024:1024 \
    -e IMPACT_ALLOWED_ORIGINS="localhost:$PORT" -p "127.0.0.1:$PORT:5006" "$IMAGE" >/dev/null
check "starts and answers /liveness" wait_live "$NAME"
check "GET /app is 200" http_ok "http://127.0.0.1:$PORT/app" 120
check "GET /liveness?endpoint=/app is 200 (builds a document)" http_ok "http://127.0.0.1:$PORT/liveness?endpoint=/app" 120
check "HEALTHCHECK kept in the image" healthcheck_in_image
check "podman healthcheck run: healthy" podman healthcheck run "$NAME"
check "image user is 10001" sh -c "[ \"\$(podman image inspect --format '{{.User}}' '$IMAGE')\" = 10001:10001 ]"
check "every process runs as uid 10001" no_root_process "$NAME"
check "writes only under /var/cache/impact (and /tmp, /var/tmp, /dev/shm)" only_cache_writable "$NAME"
check "websocket from http://evil.example is refused (403)" ws_refused http://evil.example
check "websocket from http://localhost:$PORT is admitted (101)" ws_admitted "http://localhost:$PORT"
check "server log has no traceback" no_traceback "$NAME"
podman rm -f -t 5 "$NAME" >/dev/null

# ---- refuses a wildcard origin -------------------------------------------------------
check "IMPACT_ALLOWED_ORIGINS='*' is refused (exit 64)" sh -c \
    "podman --runtime runc run --rm --pull never --health-interval disable --ulimit nofile=1024:1024 --ulimit nproc=1024:1024 -e 'IMPACT_ALLOWED_ORIGINS=*' '$IMAGE'; [ \$? -eq 64 ]"

# ---- run: read-only root, no capabilities, a volume on the cache -----------------------
say "run $HARD: --read-only, cap-drop ALL, no-new-privileges, volume on /var/cache/impact"
podman --runtime runc run -d --name "$HARD" --pull never --health-interval disable \
    --read-only --read-only-tmpfs=false \
    --cap-drop ALL --security-opt no-new-privileges \
    --ulimit nofile=1024:1024 --ulimit nproc=1024:1024 \
    -v "$VOLUME:/var/cache/impact" \
    -e IMPACT_ALLOWED_ORIGINS="localhost:$PORT" -p "127.0.0.1:$PORT:5006" "$IMAGE" >/dev/null
check "read-only: starts and answers /liveness" wait_live "$HARD"
check "read-only: GET /app is 200" http_ok "http://127.0.0.1:$PORT/app" 120
check "read-only: GET /liveness?endpoint=/app is 200" http_ok "http://127.0.0.1:$PORT/liveness?endpoint=/app" 120
check "read-only: writes only under /var/cache/impact (and /dev/shm)" only_cache_writable "$HARD" strict
check "read-only: the warmed Numba cache came with the volume" \
    podman exec "$HARD" sh -c 'find /var/cache/impact/numba -name "*.nbi" | grep .' 
check "read-only: server log has no traceback" no_traceback "$HARD"

say "summary ($(($(date +%s) - T0)) s):"
printf '  %s\n' "${RESULTS[@]}"
exit "$FAILED"
