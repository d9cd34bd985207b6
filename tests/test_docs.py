"""The manual checks itself: every ``cassi`` command line that README.md and docs/*.md show parses
with the real ``cassi`` parser (a removed flag or command fails here), every page is linked
from the README, and every relative link leads to a file that exists."""
from __future__ import annotations

import contextlib
import io
import re
import shlex
from pathlib import Path

import pytest

from cassi.harness.cli import build_parser

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]

#: What a placeholder of a synopsis stands for: a value the option's type accepts.
PLACEHOLDERS = {"N": "5", "S": "JW45", "T": "1", "V": "cassi-2.1", "NAME": "geometry",
                "NAME,...": "geometry,render", "LIST": "1-101,106"}
#: ``--subjects ...``: an example value for a list the synopsis leaves open.
ELLIPSIS = {"--subjects": "JW11", "--tasks": "1", "--versions": "cassi-2.1", "--views": "front"}
#: Where a shell command line ends: its operators and redirections.
_BREAKS = {"&&", "||", ";", "|", "&", "(", ")", "{", "}"}


def _word(token: str, previous: str) -> str:
    """One synopsis token as a real argument: brackets dropped, the first of ``{a,b}`` or
    ``a|b``, a placeholder replaced by a value of its kind."""
    token = token.strip("[]")
    if token.startswith("{") and token.endswith("}"):
        token = token[1:-1].split(",")[0]
    if "|" in token:
        token = token.split("|")[0]
    if token == "...":
        return ELLIPSIS.get(previous.strip("[]"), "x")
    return PLACEHOLDERS.get(token, token)  # DIR, RUN, FILE.csv stay: any text is a path


def _commands_in(line: str) -> list[list[str]]:
    """The ``cassi`` commands of one shell line, as argument lists (without ``cassi``)."""
    lexer = shlex.shlex(line, posix=True, punctuation_chars=True)
    lexer.whitespace_split = True
    try:
        tokens = list(lexer)
    except ValueError:  # an unclosed quote: not a shell line
        return []
    out, current, start = [], None, True
    for token in tokens:
        if token in _BREAKS or token.startswith((">", "<")):
            if current is not None:
                out.append(current)
            current, start = None, token in _BREAKS  # after a redirection: its file
            continue
        if start and Path(token).name == "cassi":
            current = []
        elif current is not None:
            current.append(token)
        start = False
    if current is not None:
        out.append(current)
    return out


def shown_commands() -> list[tuple[str, int, str, list[str]]]:
    """(page, line, the text shown, its arguments) for every ``cassi`` command in a code block or
    an inline code span of the manual."""
    found = []
    for page in PAGES:
        prose, fenced = [], False
        for number, line in enumerate(page.read_text(encoding="utf-8").splitlines(), 1):
            if line.lstrip().startswith("```"):
                fenced = not fenced
                line = ""
            elif fenced or (line.startswith("    ") and line.strip().startswith("cassi ")):
                found += [(page.name, number, line.strip(), args) for args in _commands_in(line)]
                line = ""
            prose.append(line)
        text = "\n".join(prose)
        for match in re.finditer(r"`(cassi [^`]*)`", text):  # a code span may wrap a line
            span = " ".join(match.group(1).replace("\\|", "|").split())
            words = span.split()[1:]
            found.append((page.name, text.count("\n", 0, match.start()) + 1, span,
                          [_word(w, p) for p, w in zip(["", *words], words)]))
    return found


def _subcommands(parser) -> dict:
    for action in parser._actions:  # argparse keeps its subparsers here and nowhere public
        if action.__class__.__name__ == "_SubParsersAction":
            return action.choices
    return {}


def _is_mention(args: list[str]) -> bool:
    """``cassi report`` named in prose: only command words, no arguments to check."""
    parser = build_parser()
    for word in args:
        choices = _subcommands(parser)
        if word not in choices:
            return False
        parser = choices[word]
    return True


def _parse_error(args: list[str]) -> str | None:
    stderr = io.StringIO()
    try:
        with contextlib.redirect_stderr(stderr), contextlib.redirect_stdout(io.StringIO()):
            build_parser().parse_args(args)
    except SystemExit as exit_:
        if exit_.code not in (0, None):  # 0: --help or --version
            return stderr.getvalue().strip().splitlines()[-1]
    return None


def test_every_cassi_command_the_manual_shows_parses():
    commands = shown_commands()
    assert len(commands) > 20, "found almost no cassi commands in README.md and docs/"
    wrong = []
    for page, number, text, args in commands:
        if _is_mention(args):
            continue
        error = _parse_error(args)
        if error:
            wrong.append(f"{page}:{number}: {text!r}: {error}")
    assert not wrong, "commands the manual shows that cassi refuses:\n" + "\n".join(wrong)


def test_every_cassi_command_is_shown_in_the_readme_commands():
    """The README's commands at a glance name every command (and corpus subcommand) there is."""
    shown = {tuple(args[:2]) if args[:1] == ["corpus"] else (args[0],)
             for page, _, _, args in shown_commands() if page == "README.md" and args}
    parser = build_parser()
    names = set()
    for name, sub in _subcommands(parser).items():
        inner = _subcommands(sub)
        names |= {(name, s) for s in inner} if inner else {(name,)}
    assert names - shown == set(), f"commands the README does not show: {sorted(names - shown)}"


def test_the_check_catches_a_removed_flag_and_command():
    assert _parse_error(["run", "--out", "r", "--no-such-flag"])
    assert _parse_error(["no-such-command"])
    assert _parse_error(["report", "run"])  # --out is required
    assert not _is_mention(["report", "run"])
    assert _commands_in("cd x && .venv/bin/cassi nightly --out n >> log 2>&1") == \
        [["nightly", "--out", "n"]]
    assert _commands_in("echo cassi run; cassi gc d # comment") == [["gc", "d"]]
    assert [_word(w, p) for p, w in [("", "[--stride"), ("--stride", "N]"), ("--subjects", "..."),
                                     ("--view", "{front,side}"), ("", "F.png")]] == \
        ["--stride", "5", "JW11", "front", "F.png"]


def _links(page: Path) -> list[str]:
    text = re.sub(r"```.*?```", "", page.read_text(encoding="utf-8"), flags=re.S)
    return re.findall(r"\]\(([^)\s]+)\)", text)


def test_the_readme_links_every_page_of_the_manual_and_every_link_leads_somewhere():
    pages = sorted((ROOT / "docs").glob("*.md"))
    assert pages, "docs/ holds no page"
    readme = {Path(link.split("#")[0]) for link in _links(ROOT / "README.md")}
    missing = [p.name for p in pages if p.relative_to(ROOT) not in readme]
    assert not missing, f"README.md does not link {missing}"
    broken = []
    for page in PAGES:
        for link in _links(page):
            target = link.split("#")[0]
            if not target or re.match(r"[a-z]+:", target):
                continue
            if not (page.parent / target).exists():
                broken.append(f"{page.relative_to(ROOT)}: {link}")
    assert not broken, "links to nothing:\n" + "\n".join(broken)


@pytest.mark.parametrize("page", [p for p in PAGES if p.parent.name == "docs"], ids=lambda p: p.name)
def test_each_page_leads_back_to_the_readme_and_on_to_another_page(page):
    targets = {link.split("#")[0] for link in _links(page)}
    assert "../README.md" in targets, f"{page.name} does not link the README"
    assert any(t.endswith(".md") and t != "../README.md" for t in targets), \
        f"{page.name} links no other page of the manual"
