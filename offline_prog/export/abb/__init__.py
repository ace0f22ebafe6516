"""ABB: RAPID modules (``.mod`` + ``.pgf``), the part carried past a stationary tool.

Single seam: :mod:`.rapid` (``write_rapid``). Whole job: :mod:`.rapid_job`
(``write_rapid_job``; one module with the links, seams and process I/O). ABB conventions
(controller axis values, confdata): :mod:`.abb`.
"""
