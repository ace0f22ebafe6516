"""FANUC: TP programs as LS text (``/PROG … /ATTR … /MN … /POS … /END``), flange style.

The writer: :mod:`.fanuc_ls` (``FanucPost``: a main program calling one program per
seam, with process I/O). FANUC conventions (axes, configuration strings, W-P-R, the LS
file and its /POS entries): :mod:`.fanuc`; the plan's I/O events on a seam's ``L``
points: :mod:`.fanuc_io`.
"""
