"""Procedures: what an engineer does with the rod model, one subpackage per job.

- placement/  the published placement sequence (continuation from the straight hose), the Result
              read off an equilibrium, symmetry and forks, twist paths;
- geometry/   exact distances between the hose's segments and triangles (clearance queries);
- sweep/      the placed hose carried through the motion of its mounts, clearance per pose, envelope;
- scans/      scanned hoses: centreline fitting, deviation from the model, calibration, scatter;
- variation/  variation and design studies: tolerances sampled, sensitivities, envelopes, design search.

Contact (contact/) takes its place beside these.

Imports flow one way: procedures use model/ and mechanics/, never io/, report/ or the CLI;
sweep/ and scans/ build on placement/ and geometry/, variation/ on those and sweep/; placement/ and
geometry/ use no sibling.
"""
