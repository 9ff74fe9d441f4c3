"""The report's prose: Markdown templates in templates/NAME.md, filled with computed numbers.

This is the one template mechanism of the report. A template file holds one or more named blocks:

    <!-- template: section -->
    ## A heading

    Measured order {order:.2f} ({verdict}).
    <!-- template: note -->
    A second block.

- A block starts after its marker line `<!-- template: NAME -->` and ends before the next marker
  line or at the end of the file; the newline that ends its last line belongs to the marker
  line that follows (or to the file), so a block that should end with a newline ends with an
  empty line. Text above the first marker is a comment for the reader and is not used.
- A block is filled with str.format_map: `{name}` is replaced by the value passed as `name`,
  `{name:.2f}` formats it with the format specification (the same mini-language as f-strings),
  and `{{` and `}}` stand for literal braces. Placeholders are plain names (no attributes,
  indexes or nested fields), and render() refuses a block whose placeholders and values differ.
- Templates are data: they are read as text and never evaluated. Every number and every piece
  of text that depends on a run is computed in the section's module and passed by name.
"""
import os
import re
import string

DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "templates")
_MARKER = re.compile(r"^<!-- template: ([A-Za-z0-9_]+) -->\n", re.M)
_IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_blocks = {}


def blocks(name):
    """{block name: text} of templates/NAME.md (read once)."""
    if name not in _blocks:
        with open(os.path.join(DIR, name + ".md"), encoding="utf-8") as f:
            doc = f.read()
        marks = list(_MARKER.finditer(doc))
        if not marks:
            raise ValueError(f"templates/{name}.md has no '<!-- template: NAME -->' line")
        out = {}
        for k, m in enumerate(marks):
            end = marks[k + 1].start() if k + 1 < len(marks) else len(doc)
            text = doc[m.end():end]
            if not text.endswith("\n"):
                raise ValueError(f"templates/{name}.md: block {m.group(1)} does not end with a "
                                 "newline")
            if m.group(1) in out:
                raise ValueError(f"templates/{name}.md: two blocks named {m.group(1)}")
            out[m.group(1)] = text[:-1]
        _blocks[name] = out
    return _blocks[name]


def placeholders(text):
    """The placeholder names of a block, in order of first appearance."""
    names = []
    for _, field, spec, _ in string.Formatter().parse(text):
        if field is None:
            continue
        if not _IDENT.match(field) or "{" in (spec or ""):
            raise ValueError(f"placeholder {{{field}}}: only plain names are allowed")
        if field not in names:
            names.append(field)
    return names


def render(name, block, /, **values):
    """Block `block` of templates/NAME.md with its placeholders replaced by `values`."""
    text = blocks(name)[block]
    wanted = placeholders(text)
    missing = [k for k in wanted if k not in values]
    unused = [k for k in values if k not in wanted]
    if missing or unused:
        raise KeyError(f"templates/{name}.md, block {block}: "
                       + (f"no value for {missing}" if missing else "")
                       + ("; " if missing and unused else "")
                       + (f"no placeholder for {unused}" if unused else ""))
    return text.format_map(values)
