"""The physical model of the well below the surface: the tapered rod string (FE mesh, stiffness, mass, damping),
the pump and its valve law, the produced fluid, the deviation survey, reservoir inflow and the annulus, and the
nonsmooth laws of the step problem (``laws/``: rod friction, valve, gas spring)."""
