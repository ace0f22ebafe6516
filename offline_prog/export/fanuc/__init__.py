"""FANUC: TP programs as LS text (``/PROG … /ATTR … /MN … /POS … /END``), flange style.

Single seam: :mod:`.fanuc_ls` (``write_fanuc``). Whole job: :mod:`.fanuc_job`
(``write_fanuc_job``; a main program calling one program per seam, with process I/O).
FANUC conventions (axes, configuration strings, W-P-R): :mod:`.fanuc`; the plan's I/O
events on a seam's ``L`` points: :mod:`.fanuc_io`.
"""
