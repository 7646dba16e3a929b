"""Compiled forms generated from each system's equations, written once as sympy expressions
(:mod:`.equations`): the right-hand side (:mod:`.rhs`), classical RK4's step (:mod:`.steps`)
and the Taylor coefficients' recurrences (:mod:`.series`), each written as numba source to the
compiled code's cache folder (:mod:`.build`; the product's systems' without sympy once written,
:mod:`.product`) and compiled from there."""
