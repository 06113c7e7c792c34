"""The hose parameters a calibration can fit, with their units (no solver imported: the CLI's help lists them)."""

PARAMETERS = {"bending_stiffness": "N*mm^2", "torsion_factor": "", "mass_per_length": "kg/m", "length": "mm",
              "preset_curvature": "1/mm", "preset_angle": "deg", "braid_stiffness": "N", "braid_slack": ""}
BRAID_PARAMETERS = ("braid_stiffness", "braid_slack")  # n EA_s of one family's strands, their slack strain eps0
