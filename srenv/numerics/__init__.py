"""The numerics of a time step: the compiled Newmark stepper (``kernel``) and its named calling convention
(``kernel_layout``), the certified active-set solve, the step QP through qpsolvers / ProxSuite, and the convexity
check of the step problem with nonmonotone laws."""
