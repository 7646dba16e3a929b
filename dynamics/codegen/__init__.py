"""Compiled forms generated from each system's equations, written once as sympy expressions
(:mod:`.equations`): the right-hand side (:mod:`.rhs`) and the Taylor coefficients' recurrences
(:mod:`.series`), each written to the compiled code's cache folder and compiled by numba."""
