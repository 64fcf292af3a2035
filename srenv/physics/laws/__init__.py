"""The nonsmooth laws of the step problem, one module per law (docs/kernel.md).

Each law gives, for the nodes it acts on,
  * its interval [lo_i, hi_i] (the subdifferential of its convex part j1 at 0): ``bounds`` (compiled);
  * the derivative of its smooth concave part j2 (nonmonotone laws, DC iterations): ``concave_shift``
    (compiled; it writes its own nodes of ``shift``, which the kernel has zeroed);
  * the steepest negative slope sup j2'' for the convexity check of the step problem: ``slope`` (Python);
  * a parameter record (a numpy structured array of one element, read by name in compiled code) built by
    ``make`` from physical quantities.

``rod_friction``: Coulomb / velocity-weakening mu(v) times the side force from the survey (rod nodes).
``valve``: the plunger's valve law with its fluid-pound void and velocity-weakening upstroke (pump node).
``gas_spring``: the gas in the pump chamber (or unanchored tubing) as a spring on the plunger, part of the
valve law: it replaces the valve interval by the plunger friction while enough gas is in the chamber.
"""
