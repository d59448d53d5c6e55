"""HTML building blocks: escaping, tables, key-value lists."""

import html


def esc(value):
    """Text escaped for HTML; None as an em dash."""
    return "—" if value is None else html.escape(str(value))


def table(headers, rows, *, numeric=(), bad=None, css=""):
    """An HTML table.

    Parameters
    ----------
    headers : sequence of str
    rows : sequence of sequences
        Cell values (escaped here); a cell that is `Raw` is inserted as is.
    numeric : collection of int
        Columns right-aligned with tabular figures.
    bad : callable, optional
        ``bad(row_index, column_index) -> bool``: cells to highlight.
    """
    head = "".join(f'<th class="num">{esc(h)}</th>' if k in numeric else f"<th>{esc(h)}</th>"
                   for k, h in enumerate(headers))
    body = []
    for r, row in enumerate(rows):
        cells = []
        for k, value in enumerate(row):
            classes = (["num"] if k in numeric else []) + (["bad"] if bad and bad(r, k) else [])
            attr = f' class="{" ".join(classes)}"' if classes else ""
            cells.append(f"<td{attr}>{value if isinstance(value, Raw) else esc(value)}</td>")
        body.append(f"<tr>{''.join(cells)}</tr>")
    attr = f' class="{css}"' if css else ""
    return f"<table{attr}><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"


def key_values(pairs):
    """A two-column table of (name, value) pairs."""
    rows = "".join(f"<tr><th>{esc(k)}</th><td>{v if isinstance(v, Raw) else esc(v)}</td></tr>" for k, v in pairs)
    return f'<table class="kv"><tbody>{rows}</tbody></table>'


class Raw(str):
    """HTML that is inserted without escaping."""
