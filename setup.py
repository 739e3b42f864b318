from setuptools import find_packages, setup

# The repository keeps the paper's models in the top-level folder ``models/``; they are
# installed as ``exudyn_lie.models`` (never as a top-level ``models``).  In the source
# tree ``exudyn_lie/models`` is a symbolic link to that folder, so ``exudyn_lie.models``
# imports the same files from a checkout and from an installed wheel.
setup(
    name="exudyn_lie",
    version="0.1.0",
    description=("Explicit Munthe-Kaas Lie group integrators (SE3 / SO3xR3 per body) "
                 "for constrained rigid multibody systems built with Exudyn"),
    long_description=open("README.md", encoding="utf-8").read(),
    long_description_content_type="text/markdown",
    packages=find_packages(include=["exudyn_lie", "exudyn_lie.*"], exclude=["exudyn_lie.models"])
    + ["exudyn_lie.models"],
    package_dir={"exudyn_lie.models": "models"},
    python_requires=">=3.9",
    install_requires=["exudyn>=1.13", "numpy", "numba", "matplotlib", "threadpoolctl"],
    extras_require={"test": ["pytest", "pytest-xdist", "scipy"], "bench": ["mujoco>=4.0.0"]},
    entry_points={"console_scripts": ["exudyn_lie=exudyn_lie.__main__:main"]},
)
