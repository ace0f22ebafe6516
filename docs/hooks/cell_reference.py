"""MkDocs hook: the cell file page's key table, written at build time from the schema the
loader checks cells against (offline_prog.config.key_reference), so it cannot drift."""

MARK = "<!-- cell-key-reference -->"


def on_page_markdown(markdown: str, **kwargs) -> str:
    if MARK not in markdown:
        return markdown
    from offline_prog.config.key_reference import cell_key_reference

    return markdown.replace(MARK, cell_key_reference())
