"""The control task of the v1 env: the seeded well family, one control interval of well time (exact strokes,
fast-forward, idle), the economics (USD per hour of well time) and the v0 reward."""
