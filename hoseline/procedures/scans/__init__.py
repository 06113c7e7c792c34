"""Scanned hoses against the model: centreline fitting, deviation, calibration, scatter.

centerline_fit.py reduces a point cloud to a centreline by short robust cylinder fits
(cylinder_fit.py) on the cloud's voxel grid (voxel_cloud.py: millions of points cost little);
deviation.py measures a model against points; validation.py bundles a scan comparison;
calibration.py fits stiffness (and weight, length) to scans at several twists; scatter.py
measures repeated scans; synthetic_scan.py makes scans of a known shape for tests and demos.

May import: model/, mechanics/, placement/.  Not: geometry/, sweep/, io/, report/.
"""
