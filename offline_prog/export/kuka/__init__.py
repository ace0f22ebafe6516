"""KUKA: KRL programs for KSS 8 (``name.src`` + ``name.dat``).

Single seam: :mod:`.krl` (``write_krl``; external-TCP or flange style). Whole job:
:mod:`.krl_job` (``write_krl_job``; main program plus one module per seam, with process
I/O). KUKA conventions (A, B, C, Status, Turn, the flange frame): :mod:`.kuka`; the
comment header: :mod:`.krl_header`; which plan samples become LIN points:
:mod:`.krl_points`.
"""
