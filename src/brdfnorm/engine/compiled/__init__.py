"""The compiled backend: the engine's hot loops as Numba kernels that call a model's compiled scalar BRDF
(:class:`brdfnorm.models.base.NativeKernel`) inside them.

``backend.py`` chooses the backend (``"numpy"``, the reference, or ``"compiled"``) and says once on stderr when
Numba cannot be used; ``kernels.py`` holds the kernels, written against one module-level ``shader``;
``drivers.py`` makes one copy of them per shader, in a per-user cache directory, so that Numba's on-disk cache
serves every later run (a kernel that took the shader as an argument would be compiled again in every process).
"""
