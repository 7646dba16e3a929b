"""The systems' ids in the compiled code (index of the kernels' tables), importable without numba."""

CYCLOTRON, HOOP, FREE_BODY = 0, 1, 2
#: The compiled systems by the driver's name; :mod:`mechviz.dynamics.systems`' adapters take theirs
#: from here, so each name is written once.
SYSTEM_IDS = {"cyclotron": CYCLOTRON, "hoop": HOOP, "free-body": FREE_BODY}
NAMES = {i: name for name, i in SYSTEM_IDS.items()}
