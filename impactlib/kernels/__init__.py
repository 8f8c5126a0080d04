"""Every jitted building block of a run: the closed-form flight (flight), the certified
impact search (events) and its grid form (grid), what follows an impact: flight, rest or
a chatter's tail summed (chatter), the integrators (integrators), the tangent algebra
(tangent) and the one event loop that drives them all (engine); simulate()'s entry into
it in one call (entry); a flight's lowest point for the boundary curves' grazing tests
(grazing)."""
