"""Variation and design studies: a hose as built, not as drawn.

tolerances.py turns a point of the unit hypercube into the deviations of one hose from its
drawing (mount positions and directions, length, stiffness, weight, clocking) and a problem
built with them, and correlation.py correlates tolerances by a matrix (a Gaussian copula); designs.py draws the points (Monte Carlo, Latin hypercube, Sobol);
quantities.py defines what is judged and the limits; fixed_obstacles.py measures a placement's
clearance to fixed obstacles; samples.py solves one sample (placement or sweep) and reads it; nominal.py holds the nominal placement's equilibria and starts samples from
them (warm start); engine.py runs the samples in batches on Dask distributed, and scheduler.py
checks an existing cluster's scheduler reachable before anything is solved; statistics.py turns
samples into envelopes, probabilities with confidence intervals and variances; sensitivity.py
differentiates the quantities with respect to every parameter at the nominal equilibrium
(implicit function theorem with the exact Hessian) for the first-order variance, and
sweep_sensitivity.py the same at every pose of a sweep for its extremes over the poses;
design_search.py judges and ranks hose lengths and clockings, at nominal or over the tolerances
(the clocking refined with every limit a constraint); reliability.py holds FORM, SORM (Breitung) and importance sampling in standard
normal space, and rare.py the hose's limit states for them (margins with exact gradients, the most
probable failure point of each limit); global_sensitivity.py draws the Saltelli design and estimates
Sobol' indices with bootstrap intervals; worst_case.py finds each quantity's worst-case corner;
precision.py sizes rounds of samples until a statistic is known as well as asked; study.py holds a
study and reads its outcome off the samples; run.py runs a study from start to end.

May import: model/, mechanics/, placement/, geometry/, sweep/.  Not: scans/, io/, report/.
"""
