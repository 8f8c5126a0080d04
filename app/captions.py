"""The sentence under the title: what is on screen, in words.

While the settings that change what is computed are those of the scene loaded (or the
paper's defaults), the caption is that scene's; after a change it is one line naming
what differs ("**Fig. 2** with ω = 2.75"). A run that starts on a periodic orbit (a tap
on a branch or a boundary curve, ``app.orbit_pick``) is named as that orbit. Display settings, the branch overlay and the
research settings change nothing in it (``state.differences``).
"""
from __future__ import annotations

from .orbit_pick import describe
from .scenes import BY_KEY
from .settings import BY_NAME
from .state import differences

DEFAULT_CAPTION = ("Paper defaults: m = 1, c = 0.05, k = 1, g = 0, r = 0.8, ω = 2. "
                   "Pick a scene of the paper or move a slider.")


def symbol(name: str) -> str:
    """How the page writes a setting: its label's symbol (ω, ψ/T, x₀) or its name."""
    label = BY_NAME[name].label
    return label.split("  ")[0] if "  " in label else name


def value_text(name: str, value) -> str:
    if value is None:
        return "empty (at the wall)" if name == "x0" else "empty"
    if isinstance(value, bool):
        return "on" if value else "off"
    if isinstance(value, float):
        return f"{value:g}".replace("-", "−")
    return str(value)


def title(scene: str | None) -> str:
    """Short name of a scene ("Fig. 7a") or of the defaults."""
    if scene is None:
        return "Paper defaults"
    return BY_KEY[scene].label.split(" · ")[0].replace("Fig ", "Fig. ")


def caption(run, scene: str | None) -> str:
    """The caption (Markdown) for ``run`` shown after loading ``scene`` (None: the
    defaults)."""
    changed = differences(run, scene)
    if not changed:
        return BY_KEY[scene].caption if scene else DEFAULT_CAPTION
    return f"**{title(scene)}** with " + ", ".join(
        f"{symbol(n)} = {value_text(n, v)}" for n, v in changed.items())


def orbit_caption(run, start) -> str:
    """The caption of ``run`` starting on a periodic orbit (``orbit_pick.OrbitStart``):
    the orbit at the diagram's and the regime map's parameters."""
    names = dict.fromkeys((run.bif_param, run.map_x, run.map_y))
    return describe(start, {n: symbol(n) for n in names})
