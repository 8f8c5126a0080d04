"""Analyses of one parameter set, each a function f(p, ...) -> frozen result: periodic
orbits (orbits), Lyapunov exponents (lyapunov), the (m, n) classification (classify),
branches of orbits (continuation), their events followed in two parameters (boundary)
and basins of attraction (basins)."""
