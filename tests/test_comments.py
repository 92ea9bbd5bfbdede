"""Comments and docstrings say what and why, not history: no dates and no issue numbers in src/ (git keeps those)."""
import ast
import io
import re
import tokenize

from conftest import WORKSPACE

SOURCES = WORKSPACE / "src"
#: a calendar date (2026-11-23) or a reference to an issue ("issue 5", "issues 3 and 4", "issue #7")
HISTORY = re.compile(r"\b20\d\d-\d\d-\d\d\b|\bissues? #?\d+", re.IGNORECASE)


def _comments_and_docstrings(source: str):
    """(line, text) of every comment and every string statement (module, class, function and attribute
    docstrings) of one Python source."""
    for token in tokenize.generate_tokens(io.StringIO(source).readline):
        if token.type == tokenize.COMMENT:
            yield token.start[0], token.string
    for node in ast.walk(ast.parse(source)):
        body = getattr(node, "body", None)
        for statement in body if isinstance(body, list) else []:
            if isinstance(statement, ast.Expr) and isinstance(statement.value, ast.Constant) \
                    and isinstance(statement.value.value, str):
                for offset, text in enumerate(statement.value.value.splitlines()):
                    yield statement.lineno + offset, text


def test_no_dates_or_issue_numbers_in_comments_and_docstrings():
    found = []
    for path in sorted(SOURCES.rglob("*.py")):
        for line, text in _comments_and_docstrings(path.read_text()):
            if HISTORY.search(text):
                found.append(f"{path.relative_to(WORKSPACE)}:{line}: {text.strip()}")
    assert not found, "history in comments or docstrings (say what and why instead):\n" + "\n".join(found)


def test_no_issue_numbers_in_package_descriptions():
    found = []
    for path in sorted(SOURCES.glob("*/package.xml")) + sorted(SOURCES.glob("*/setup.py")):
        for line, text in enumerate(path.read_text().splitlines(), start=1):
            if HISTORY.search(text):
                found.append(f"{path.relative_to(WORKSPACE)}:{line}: {text.strip()}")
    assert not found, "history in package descriptions:\n" + "\n".join(found)
