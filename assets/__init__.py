"""The data shipped with mechviz (the built-in demos, the benchmark's references, the viewer's maps
of the default hoop), read through :func:`mechviz.dynamics.assets.asset`."""
