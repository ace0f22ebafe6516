"""KUKA: KRL programs for KSS 8 (``name.src`` + ``name.dat``, one module per seam).

The writer: :mod:`.krl` (``KrlPost``: external-TCP style, process I/O on the path).
KUKA conventions (A, B, C, Status, Turn, the flange frame, ``$VEL.CP``): :mod:`.kuka`.
"""
