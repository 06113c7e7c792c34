"""The hose parameters a calibration can fit, with their units (no solver imported: the CLI's help lists them)."""

PARAMETERS = {"bending_stiffness": "N*mm^2", "torsion_factor": "", "mass_per_length": "kg/m", "length": "mm",
              "preset_curvature": "1/mm", "preset_angle": "deg"}
