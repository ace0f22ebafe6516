"""Reading a written RAPID module back, as the tests do: its PROCs' statements."""


def rapid_procs(text: str) -> dict[str, list[str]]:
    """PROC name ↦ its statements (stripped lines between ``PROC`` and ``ENDPROC``,
    comments included), in the module's order."""
    procs, current = {}, None
    for raw in text.splitlines():
        line = raw.strip()
        if line.startswith("PROC "):
            current = procs.setdefault(line.split()[1].split("(")[0], [])
        elif line.startswith("ENDPROC"):
            current = None
        elif current is not None:
            current.append(line)
    return procs
