"""Read the project's Dockerfile and state what the image must guarantee.

`parse` turns a Dockerfile into instructions (continuation lines joined, comments
dropped, `# hadolint ignore=` pragmas kept); `walk` follows ENV, ARG, WORKDIR and USER
through them the way a builder does; `problems` lists every broken promise of the
container (non-root, health check, pinned base, origins and process count from
configuration, port,
warmed Numba cache, pinned installs). The tests run `problems` on the real Dockerfile
and on broken copies of it, so every check is seen to fail when it should.
"""

from __future__ import annotations

import json
import re
import shlex
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
DOCKERFILE = REPO / "Dockerfile"
DOCKERIGNORE = REPO / ".dockerignore"
PORT = 5006
# PATH inside debian:bookworm-slim before the Dockerfile changes it.
BASE_PATH = "/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin"
# Rules the Dockerfile may silence inline, with the reason it gives.
ALLOWED_HADOLINT_IGNORES = {
    "DL3008": "ca-certificates is left to track Debian's security updates",
}
FORBIDDEN_SERVE_FLAGS = ("--admin", "--autoreload", "--dev", "--show")


@dataclass(frozen=True)
class Instruction:
    keyword: str  # upper case: FROM, RUN, ...
    args: str  # everything after the keyword, continuation lines joined
    line: int  # 1-based line of the keyword
    ignores: tuple[str, ...] = ()  # codes from a `# hadolint ignore=` right above

    def exec_form(self) -> list[str] | None:
        """The JSON array of an exec-form CMD/ENTRYPOINT/RUN, else None."""
        text = self.args.strip()
        if not text.startswith("["):
            return None
        value = json.loads(text)
        if not (isinstance(value, list) and all(isinstance(v, str) for v in value)):
            raise ValueError(f"line {self.line}: exec form must be a JSON list of strings")
        return value


def parse(text: str) -> list[Instruction]:
    lines = text.splitlines()
    out: list[Instruction] = []
    ignores: list[str] = []
    i = 0
    while i < len(lines):
        stripped = lines[i].strip()
        if not stripped:
            i += 1
            continue
        if stripped.startswith("#"):
            m = re.match(r"#\s*hadolint\s+ignore=([A-Z0-9, ]+)$", stripped)
            if m:
                ignores += [c.strip() for c in m.group(1).split(",") if c.strip()]
            i += 1
            continue
        start = i + 1
        joined = ""
        while i < len(lines):
            line = lines[i].rstrip()
            i += 1
            if line.endswith("\\"):
                joined += line[:-1]
                while i < len(lines) and lines[i].strip().startswith("#"):
                    i += 1  # comments inside a continued instruction are dropped
                continue
            joined += line
            break
        keyword, _, args = joined.strip().partition(" ")
        out.append(Instruction(keyword.upper(), args.strip(), start, tuple(ignores)))
        ignores = []
    return out


_VAR = re.compile(r"\$\{(\w+)\}|\$(\w+)")


def expand(value: str, env: dict[str, str]) -> str:
    """Substitute ${NAME} and $NAME as Dockerfile ENV/ARG/COPY/WORKDIR do."""
    return _VAR.sub(lambda m: env.get(m.group(1) or m.group(2), ""), value)


def assignments(args: str) -> list[tuple[str, str]]:
    """`K=V K2="V 2"` (ENV, ARG) as (name, unexpanded value) pairs."""
    pairs = []
    for word in shlex.split(args, posix=True):
        name, eq, value = word.partition("=")
        pairs.append((name, value if eq else ""))
    return pairs


@dataclass
class Step:
    instruction: Instruction
    env: dict[str, str]  # ENV and ARG values in force at this instruction
    workdir: str
    user: str


def walk(
    instructions: list[Instruction],
    rewrite: Callable[[str], str] = lambda v: v,
    base_env: dict[str, str] | None = None,
) -> Iterator[Step]:
    """Follow the build state; `rewrite` maps a literal absolute path set by ENV, ARG
    or WORKDIR (so a replay can move /opt/venv under a temporary root)."""
    env = dict(base_env if base_env is not None else {"PATH": BASE_PATH})
    workdir, user = rewrite("/"), "root"
    for ins in instructions:
        yield Step(ins, dict(env), workdir, user)
        if ins.keyword in ("ENV", "ARG"):
            before = dict(env)  # one ENV sees only the values set before it
            for name, raw in assignments(ins.args):
                if ins.keyword == "ARG" and not raw:
                    continue
                value = rewrite(raw) if raw.startswith("/") else raw
                env[name] = expand(value, before)
        elif ins.keyword == "WORKDIR":
            raw = ins.args.strip()
            if raw.startswith("/"):
                workdir = expand(rewrite(raw), env)
            elif raw.startswith("$"):
                workdir = expand(raw, env)
            else:
                workdir = str(Path(workdir) / expand(raw, env))
        elif ins.keyword == "USER":
            user = ins.args.strip()


def final_env(instructions: list[Instruction]) -> dict[str, str]:
    step = None
    for step in walk(instructions + [Instruction("NOP", "", 0)]):
        pass
    assert step is not None
    return step.env


def serve_command(instructions: list[Instruction]) -> list[str]:
    cmds = [i for i in instructions if i.keyword == "CMD"]
    if not cmds:
        raise ValueError("no CMD")
    form = cmds[-1].exec_form()
    if form is None:
        raise ValueError("CMD is not in exec form")
    return form


def healthcheck_command(ins: Instruction) -> list[str] | None:
    _, sep, rest = ins.args.partition("CMD ")
    if not sep:
        return None
    return Instruction("CMD", rest, ins.line).exec_form() or ["/bin/sh", "-c", rest]


def image_ref(from_args: str) -> tuple[str, str | None, str | None]:
    """(name, tag, digest) of `FROM [--platform=..] image[:tag][@digest] [AS x]`."""
    words = [w for w in from_args.split() if not w.startswith("--")]
    ref = words[0]
    ref, _, digest = ref.partition("@")
    last = ref.rsplit("/", 1)[-1]
    tag = last.partition(":")[2] or None
    name = ref[: len(ref) - len(tag) - 1] if tag else ref
    return name, tag, digest or None


def pip_install_commands(run_args: str) -> list[list[str]]:
    """Each `pip install ...` inside a RUN (shell form), as its argument words."""
    lexer = shlex.shlex(run_args, posix=True, punctuation_chars=";&|")
    lexer.whitespace_split = True
    commands: list[list[str]] = [[]]
    for token in lexer:
        if token in (";", "&&", "||", "|", "&"):
            commands.append([])
        else:
            commands[-1].append(token)
    out = []
    for words in commands:
        for k, w in enumerate(words):
            if w == "install" and k > 0 and Path(words[k - 1]).name.startswith("pip"):
                out.append(words[k + 1 :])
    return out


def problems(text: str) -> list[str]:
    """Every way the Dockerfile in `text` breaks the container's promises."""
    found: list[str] = []
    ins = parse(text)
    by = {kw: [i for i in ins if i.keyword == kw] for kw in {i.keyword for i in ins}}
    env = final_env(ins)

    for i in ins:
        for code in i.ignores:
            if code not in ALLOWED_HADOLINT_IGNORES:
                found.append(f"line {i.line}: hadolint rule {code} silenced without a reason on record")

    froms = by.get("FROM", [])
    if not froms:
        found.append("no FROM")
    else:
        name, tag, digest = image_ref(froms[-1].args)
        if not digest and (tag is None or tag == "latest"):
            found.append(f"base image {froms[-1].args!r} is not pinned by a tag (or digest)")
        if name.split("/")[-1] != "debian" or not (tag or "").startswith("bookworm"):
            found.append(f"base image {froms[-1].args!r} is not debian:bookworm*")

    users = by.get("USER", [])
    if not users:
        found.append("no USER: the server would run as root")
    else:
        who = users[-1].args.split(":")[0].strip()
        if who in ("root", "0", ""):
            found.append(f"final USER {users[-1].args!r} is root")

    health = by.get("HEALTHCHECK", [])
    if len(health) != 1:
        found.append(f"expected one HEALTHCHECK, found {len(health)}")
    else:
        hc = healthcheck_command(health[0])
        if hc is None or health[0].args.strip().upper() == "NONE":
            found.append("HEALTHCHECK has no command")
        elif not any("/liveness" in w and f":{PORT}" in w for w in hc):
            found.append(f"HEALTHCHECK does not query http://127.0.0.1:{PORT}/liveness")

    exposed = {p.split("/")[0] for e in by.get("EXPOSE", []) for p in e.args.split()}
    if str(PORT) not in exposed:
        found.append(f"EXPOSE {PORT} missing")

    try:
        cmd = " ".join(serve_command(ins))
    except ValueError as e:
        found.append(str(e))
        cmd = ""
    if cmd:
        if "panel serve" not in cmd or "app/app.py" not in cmd:
            found.append("CMD does not run `panel serve app/app.py`")
        if not re.search(rf"--port[= ]{PORT}\b", cmd):
            found.append(f"CMD does not serve on port {PORT}")
        if "--liveness" not in cmd:
            found.append("CMD lacks --liveness (the health check needs /liveness)")
        for flag in FORBIDDEN_SERVE_FLAGS:
            if re.search(rf"{flag}\b", cmd):
                found.append(f"CMD turns on {flag}")
        if "IMPACT_ALLOWED_ORIGINS" not in cmd or "--allow-websocket-origin" not in cmd:
            found.append("CMD does not take the websocket origins from IMPACT_ALLOWED_ORIGINS")
        if re.search(r"""--allow-websocket-origin[= ]+["']?\*""", cmd):
            found.append("CMD allows websocket origin *")
        if not re.search(r'--num-procs[= ]+"?\$\{?IMPACT_PROCS\b', cmd):
            found.append("CMD does not take its process count (--num-procs) from IMPACT_PROCS")
    origins = env.get("IMPACT_ALLOWED_ORIGINS")
    if origins is None:
        found.append("no default IMPACT_ALLOWED_ORIGINS in ENV")
    elif "*" in origins or not origins.strip():
        found.append(f"default IMPACT_ALLOWED_ORIGINS={origins!r} is open or empty")
    procs = env.get("IMPACT_PROCS")
    if procs is None:
        found.append("no default IMPACT_PROCS in ENV")
    elif not (procs.isdigit() and int(procs) >= 1):
        found.append(f"default IMPACT_PROCS={procs!r} is not a whole number >= 1")
    if "*" in env.get("BOKEH_ALLOW_WS_ORIGIN", ""):
        found.append("BOKEH_ALLOW_WS_ORIGIN allows *")

    cache = env.get("NUMBA_CACHE_DIR", "")
    if not cache:
        found.append("NUMBA_CACHE_DIR is not set")
    elif cache.startswith((env.get("VIRTUAL_ENV", "/opt/venv"), "/tmp", "/usr", "/opt")):
        found.append(f"NUMBA_CACHE_DIR={cache} is not a cache directory of its own")
    runs = by.get("RUN", [])
    if not any("NUMBA_CACHE_DIR" in r.args and re.search(r"(-o|chown)\s+\S+", r.args) for r in runs):
        found.append("no RUN gives NUMBA_CACHE_DIR to the serving user")
    final_user_line = users[-1].line if users else 1 << 30
    warm = [
        r
        for r in runs
        if "import impactlib" in r.args and "simulate(" in r.args and "bifurcation(" in r.args
    ]
    if not warm:
        found.append("no RUN warms the Numba cache (import impactlib; simulate; bifurcation)")
    elif not any(r.line > final_user_line for r in warm):
        found.append("the Numba cache is warmed before USER, so the server's user would not own it")

    pips = [(r, words) for r in runs for words in pip_install_commands(r.args)]
    if not pips:
        found.append("no RUN pip install")
    for r, words in pips:
        if "--no-cache-dir" not in words:
            found.append(f"line {r.line}: pip install without --no-cache-dir")
        if "-e" in words or "--editable" in words:
            found.append(f"line {r.line}: editable install in the image")
        for w in words:
            if w.startswith("-"):
                continue
            if not (w.startswith(("$", "/", ".")) or "==" in w):
                found.append(f"line {r.line}: pip install {w!r} is not pinned with ==")
    return found


def dockerignore_problems(ignore_text: str, dockerfile_text: str) -> list[str]:
    """The build context must be an allowlist that still holds every COPY source."""
    found = []
    patterns = [
        ln.strip() for ln in ignore_text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")
    ]
    if not patterns or patterns[0] != "*":
        found.append(".dockerignore does not start by excluding everything ('*')")
    included = {p[1:].rstrip("/") for p in patterns if p.startswith("!")}
    for i in parse(dockerfile_text):
        if i.keyword != "COPY" or "--from" in i.args:
            continue
        for src in shlex.split(i.args)[:-1]:
            if src.startswith("--"):
                continue
            if src.rstrip("/") not in included:
                found.append(f".dockerignore leaves out {src}, which line {i.line} COPYs")
    return found
