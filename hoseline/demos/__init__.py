"""The built-in examples: the thesis brake hose (thesis_hose.py), its sweep past a strut
(sweep.py), and synthetic scans of it compared and calibrated (validation.py).

They sit above io/ and report/ (they write files) and below the CLI.
"""
