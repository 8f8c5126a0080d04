"""Independent checks of the core: the mpmath and solve_ivp references (reference),
impact matching and error metrics (compare), the accuracy report (report, accuracy)."""
