"""Running a well: the simulator (assembles the model, runs strokes through the kernel, calls the step QP), the
pump valve cycle between kernel calls, what a run returns, and the Hopf threshold of velocity-weakening friction
(spring-block and rod string)."""
