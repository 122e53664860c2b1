"""One colour per lattice in every figure of the project (paper figures, suite plots, paths)."""

LATTICE_COLORS = {"cubic": "tab:grey", "bcc": "tab:blue", "fcc": "tab:green",
                  "mcc": "tab:purple", "hex": "tab:orange"}
"""Matplotlib colour of each named lattice; other lattices (custom) use ``OTHER_COLOR``."""

OTHER_COLOR = "tab:red"
