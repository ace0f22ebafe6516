"""Universal Robots: URScript programs (one ``.script``), the planned joints streamed.

The writer: :mod:`.urscript` (``UrScriptPost``: ``movej`` links, each seam with its
approach and retract streamed with ``servoj``, process I/O).
"""
