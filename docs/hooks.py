"""mkdocs hook: replace ``<!-- gen:NAME -->`` lines with tables generated from the
code (docs/gen.py), so the options, markers, KPIs, CLI, layers, stepping order, blueprints,
computers and limits in the docs are the code's own."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

_spec = importlib.util.spec_from_file_location("flockai_docs_gen", Path(__file__).with_name("gen.py"))
gen = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(gen)

_MARK = re.compile(r"^<!-- gen:([a-z_]+) -->$", re.M)


def on_page_markdown(markdown, page, config, files):
    def table(m: re.Match) -> str:
        name = m.group(1)
        if name not in gen.TABLES:
            raise KeyError(f"{page.file.src_path}: unknown generated table {name!r}; "
                           f"known: {sorted(gen.TABLES)}")
        return gen.TABLES[name]()
    return _MARK.sub(table, markdown)
