"""The commands of the hoseline command line, one module each; common.py holds what they share
(exit codes, errors, progress), scan_inputs.py what compare and calibrate share.  hoseline.cli
assembles them into one app."""
