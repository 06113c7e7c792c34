"""Placement by continuation (Keil & Thomas) and what a placed hose reports.

sequence.py is the published sequence (translate and rotate the free end with its roll free,
lock, twist), path.py the clamps along it (PlacementPath); continuation.py follows a path of clamps with forks and stability handled;
stations.py and hose_health.py read bend radius, moments and reactions off an equilibrium
into a Result (result.py); symmetry.py lists mirror images; stiffening.py phases in the
thesis' stiffener springs; twist_path.py twists a placed hose step by step.

May import: model/, mechanics/.  Not: geometry/, sweep/, scans/, io/, report/.
"""
