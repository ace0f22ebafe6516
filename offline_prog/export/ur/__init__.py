"""Universal Robots: URScript programs (one ``.script``), the planned joints streamed.

Single seam: :mod:`.urscript` (``write_urscript``; ``servoj`` at the controller period,
or ``movel`` poses of the part). Whole job: :mod:`.urscript_job`
(``write_urscript_job``; ``movej`` links, streamed seams, process I/O).
"""
