"""The systems' ids in the compiled code (index of the kernels' tables), importable without numba."""

CYCLOTRON, HOOP, FREE_BODY = 0, 1, 2
SYSTEM_IDS = {"cyclotron": CYCLOTRON, "hoop": HOOP, "free-body": FREE_BODY}
