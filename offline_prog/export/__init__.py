"""Controller programs and trajectory files from a finished plan (issue: exports).

``program.ProgramData`` is what every writer reads; ``density.select_points``
picks Cartesian points within a chordal and an orientation tolerance.
"""
