"""Package discovery (the rest of the metadata is in pyproject.toml): every package under
warpbem/ found by setuptools, and the top-level kernels/ folder (Warp device code, DESIGN.md
§2) installed as warpbem.kernels, so no subpackage is listed by hand and none is forgotten; and
the data files the package reads (the accuracy target's error model)."""

from setuptools import find_packages, setup

kernels = ["warpbem.kernels"] + [f"warpbem.kernels.{p}" for p in find_packages("kernels")]
setup(packages=find_packages(include=["warpbem", "warpbem.*"]) + kernels,
      package_dir={"warpbem.kernels": "kernels"}, package_data={"warpbem.hydro": ["error_model_table.json"]})
