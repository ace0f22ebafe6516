"""ABB: RAPID modules (``.mod`` + ``.pgf``), the part carried past a stationary tool.

The writer: :mod:`.rapid` (``RapidPost``: one module with the links, seams and process
I/O). ABB conventions (controller axis values, confdata): :mod:`.abb`.
"""
