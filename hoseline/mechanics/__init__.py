"""The discrete rod: energy, derivatives, Newton, stability (compiled kernels).

Importing the package first points Numba's cache at hoseline/compilation.py's folder for this
version of the kernel sources, before any kernel is defined: no kernel is ever loaded stale.
"""

from hoseline import compilation

compilation.install()
