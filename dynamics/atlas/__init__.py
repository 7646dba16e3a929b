"""The stability atlas: maps over a grid of starts or settings, each cell a full run of a compiled
method, computed in chunks on a Dask cluster and kept in a Zarr store.

- :mod:`.grid`: what an atlas is (:class:`AtlasSpec`: kind, system, methods, axes, chunks);
- :mod:`.theory`: the start each amplitude means and the lines theory draws over the maps;
- :mod:`.kernels`: the work of one chunk (stability, chaos, accuracy);
- :mod:`.store`: the xarray Dataset in Zarr, written chunk by chunk;
- :mod:`.driver`: the Dask run (:func:`run_atlas`) and the serial one (:func:`compute_serial`);
- :mod:`.maps`: PNG and SVG maps;
- :mod:`.bench`: the cost per cell, parallel efficiency and scheduling overhead.

Needs the ``atlas`` extra (``pip install 'mechviz-lab[atlas]'``: dask, distributed, xarray, zarr).
Never imports viser.
"""

from .grid import AtlasSpec, Axis
from .kernels import compute_chunk

__all__ = ["AtlasSpec", "Axis", "compute_chunk"]
