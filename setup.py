"""Finds the packages: each layer folder installs as ``cassi.<layer>`` with its subpackages, so a
new subpackage needs no edit anywhere (the rest of the metadata is in pyproject.toml)."""
from setuptools import find_packages, setup

LAYERS = ("common", "data", "versions", "renderer", "harness", "reports")

setup(packages=[f"cassi.{p}" for p in find_packages(include=[f"{layer}*" for layer in LAYERS])],
      package_dir={"cassi": "."})
