"""The paper's figures as one-click scenes (Lee, "Motion behavior of impact oscillator").

Every scene starts from the paper's settings (m = 1, c = 0.05, k = 1, g = 0, r = 0.8,
integrated to 500 s with the first 250 s discarded, exact method) and changes only what
the figure states. Fig. 7 gives the section as "φ = π/4ω", i.e. π/(4ω) in time units,
which is T/8: the settings hold ψ as a fraction of T, so ψ/T = 1/8, 3/8, 5/8, 7/8.
"""
from __future__ import annotations

import dataclasses

BASE = {"m": 1.0, "c": 0.05, "k": 1.0, "g": 0.0, "r": 0.8, "omega": 2.0, "psi": 0.0,
        "t_end": 500.0, "t_record": 250.0, "x0": None, "v0": 0.0, "method": "exact",
        "bif_param": "omega", "bif_sweep": "independent", "bif_min": 0.1,
        "bif_max": 5.0, "bif_n": 400}


@dataclasses.dataclass(frozen=True)
class Scene:
    key: str
    label: str
    changes: dict
    caption: str

    def settings(self) -> dict:
        return {**BASE, **self.changes}


SCENES: tuple[Scene, ...] = (
    Scene("fig2", "Fig 2 · ω=2", {"omega": 2.0},
          "**Fig. 2, ω = 2 (impact resonance ω = 2ωₙ).** Look for one impact per period: "
          "a closed loop in the phase plane with a vertical jump at the wall, a single "
          "point in the impact map and a single point in the Poincaré map "
          "(1-impact period-1)."),
    Scene("fig4", "Fig 4 · ω=0.2", {"omega": 0.2},
          "**Fig. 4, ω = 0.2: complete chattering.** In each long period (T ≈ 31 s) the "
          "mass hits the wall, bounces ever lower, sticks to it until the force pulls it "
          "away, then flies off and returns. Look for a cloud of impacts whose velocity "
          "shrinks to zero in the impact map, and one Poincaré point (period-1)."),
    Scene("fig5", "Fig 5 · ω=1.2", {"omega": 1.2, "t_end": 3000.0, "t_record": 2500.0},
          "**Fig. 5, ω = 1.2: incomplete chattering.** The mass leaves the wall after a "
          "few impacts without sticking: 3 clusters in the impact map and 2 Poincaré "
          "points (3-impact period-2). *What we found:* in the paper's window "
          "(250–500 s) our exact solution is still in a long chaotic transient; it "
          "settles on the paper's 3-impact period-2 orbit later, so this scene shows "
          "2500–3000 s. Set the window back to 250–500 s to see the transient."),
    Scene("fig6", "Fig 6 · ω=2.8", {"omega": 2.8},
          "**Fig. 6, ω = 2.8: chaotic chattering.** No repeating pattern: the impact map "
          "and the Poincaré map fill out a strange attractor (∞-impact period-∞)."),
    *(Scene(f"fig7{letter}", f"Fig 7{letter} · ψ={num}T/8", {"omega": 2.8, "psi": num / 8},
            f"**Fig. 7({letter}), ω = 2.8, Poincaré section ψ = {num}π/(4ω) = {num}T/8.** "
            "The same chaotic motion as Fig. 6 cut at another phase: watch the attractor "
            "fold and twist from section to section (drag ψ to see it move).")
      for letter, num in zip("abcd", (1, 3, 5, 7))),
    *(Scene(f"fig3{letter}", f"Fig 3{letter} · r={r:g}", {"r": r},
            f"**Fig. 3({letter}), r = {r:g}: bifurcation diagram over ω.** "
            + note)
      for letter, r, note in (
          ("a", 0.0, "All energy is lost at impact and the mass sticks to the wall. Look for "
                     "the impact resonance at ω ≈ 1, the free oscillation (we find the "
                     "largest impact speed at ω ≈ 1.02), and the end of 1-impact "
                     "period-1 motion near ω ≈ 2.7 (paper: period doubling at 2.6), "
                     "with 1-impact period-2 from about ω = 3.05."),
          ("b", 0.2, "Low restitution: the resonance peak is still at ω ≈ 1 (we find "
                     "1.02); compare with r = 0 and r = 0.4."),
          ("c", 0.4, "The peak starts to move from ω ≈ 1 towards ω ≈ 2 as r grows (we "
                     "find it at ω ≈ 1.12)."),
          ("d", 0.6, "The impact resonance is now at ω ≈ 2ωₙ = 2 (we find 1.96). One "
                     "impact per period up to ω ≈ 2.7 (paper: 2.6), then two impacts "
                     "(2-impact period-2), then chaos from ω ≈ 2.8."),
          ("e", 0.8, "The paper's default r: the resonance at ω = 2 (Fig. 2), period-1 "
                     "motion up to ω ≈ 2.6, then a band of chattering and chaos around "
                     "ω = 2.8 (Fig. 6)."),
          ("f", 0.9, "Nearly elastic impacts: the largest impact speeds of all panels at "
                     "ω ≈ 2, and many windows of multi-impact motion below ω = 1.3."),
      )),
)

BY_KEY = {s.key: s for s in SCENES}
