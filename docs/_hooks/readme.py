"""MkDocs hook: the site's home page is the README. docs/index.md holds only the mark
`<!-- readme -->`, which becomes README.md with its links made relative to docs/ when the site
is built, so the front page and the repository's door never say two things."""

from __future__ import annotations

from pathlib import Path
from typing import Any

MARK = "<!-- readme -->"
README = Path(__file__).resolve().parents[2] / "README.md"


def readme_for_site(text: str) -> str:
    """The README as a page of the site: its links into docs/ relative to it, and the changelog
    (outside docs/) named instead of linked."""
    return (text.replace("](docs/", "](")
            .replace("[CHANGELOG.md](CHANGELOG.md)", "`CHANGELOG.md` beside the README"))


def on_page_markdown(markdown: str, **_: Any) -> str:
    if MARK not in markdown:
        return markdown
    return markdown.replace(MARK, readme_for_site(README.read_text(encoding="utf-8")))
