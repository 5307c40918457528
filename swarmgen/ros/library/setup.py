"""ament_python package swarmgen_library: `colcon build`, or put this folder on PYTHONPATH."""

from setuptools import setup  # type: ignore[import-untyped,unused-ignore]

PACKAGE = "swarmgen_library"

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=[PACKAGE],
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
    ],
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="swarmgen",
    maintainer_email="swarmgen@example.com",
    description="swarmgen's behaviour library and continuous world for the detailed simulation",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            f"world = {PACKAGE}.world_node:main",
            f"servers = {PACKAGE}.servers:main",
        ]
    },
)
