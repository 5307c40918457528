"""The statements of the expression language: actions (effects, entry and exit) on the
expression parser (`parse`): assignments, `raise`/`send` (delays, targets, send ids), `cancel`,
`if`/`elif`/`else`, `for`, `block`, `done`, `log` (docs/profile.md)."""

from __future__ import annotations

from swarmgen.expr.errors import error_at
from swarmgen.expr.lex import Tok
from swarmgen.expr.parse import _Parser, _show_tok
from swarmgen.expr.tree import (
    EVENT_NAME,
    RESERVED,
    Action,
    Arg,
    Assign,
    Attr,
    Block,
    Branch,
    Cancel,
    Const,
    Delay,
    DelayUnit,
    Done,
    Expr,
    ForEach,
    If,
    Log,
    Name,
    Operand,
    Raise,
    Send,
)

_NOT_ACTION = (
    "an action must be `name = expression`, `raise <event>(...)`, `send <event>(...)` or "
    "`cancel <name>`"
)
_BRANCH_ENDS = frozenset({"elif", "else", "end"})


class _StatementParser(_Parser):
    """The expression parser with the statements of effects, entry and exit actions."""

    @staticmethod
    def is_word(text: str, tok: Tok) -> bool:
        return tok.kind == "word" and tok.text == text

    def action(self) -> Action:
        tok = self.peek()
        # `send = 1` assigns member data named `send`
        if (
            tok.kind == "word"
            and tok.text in ("raise", "send", "cancel", "if", "for", "done", "log", "block")
            and not self.is_op("=", self.peek(1))
        ):
            if tok.text == "block":
                opening = self.advance()
                self.enter(opening)
                actions = self.block(opening)
                closing = self.advance()
                if closing.text != "end":
                    self.fail(
                        closing, f"'{closing.text}' in a block", hint="a block ends with 'end'"
                    )
                self.nest -= 1
                return Block(actions=actions)
            if tok.text == "log":
                return self.log()
            if tok.text == "done":
                self.advance()
                if not self.is_op("(", self.peek()):
                    self.fail(self.peek(), "`done` needs its fields: done(f = expr, ...)")
                named = self.peek(1).kind == "word" and self.is_op("=", self.peek(2))
                if named or self.is_op(")", self.peek(1)):
                    return Done(args=self.arguments())
                opening = self.advance()  # `done(expr)`: the data is the value itself
                content, _ = self.expr(0)
                self.close(opening)
                return Done(content=content)
            if tok.text == "if":
                return self.conditional()
            if tok.text == "for":
                return self.loop()
            return self.cancel() if tok.text == "cancel" else self.event_action()
        target, value = self.assignment(_NOT_ACTION)
        return Assign(target=target, value=value)

    def conditional(self) -> If:
        """`if c then ... elif c then ... else ... end` (statements as anywhere else)."""
        opening = self.advance()
        self.enter(opening)
        branches: list[Branch] = []
        keyword = opening
        while True:
            cond: Expr | None = None
            if keyword.text != "else":
                cond, _ = self.expr(0)
                if not self.is_word("then", self.peek()):
                    self.fail(
                        self.peek(), f"expected 'then' after the condition of '{keyword.text}'"
                    )
                self.advance()
            branches.append(Branch(cond=cond, actions=self.block(opening)))
            keyword = self.advance()  # elif, else or end: `block` stopped at one
            if keyword.text == "end":
                break
            if branches[-1].cond is None:
                self.fail(
                    keyword, f"'{keyword.text}' after 'else'", hint="`else` is the last branch"
                )
        self.nest -= 1
        return If(branches=tuple(branches))

    def log(self) -> Log:
        """`log expr` or `log "label", expr`."""
        self.advance()
        first, _ = self.expr(0)
        if not self.is_op(",", self.peek()):
            return Log(value=first)
        comma = self.advance()
        if not (isinstance(first, Const) and isinstance(first.value, str)):
            self.fail(comma, 'a log\'s label is a string: log "label", expr')
        value, _ = self.expr(0)
        return Log(label=first.value, value=value)

    def loop(self) -> ForEach:
        """`for item[, index] in array do ... end`."""
        opening = self.advance()
        self.enter(opening)
        names: list[str] = []
        while True:
            tok = self.peek()
            if tok.kind != "word" or tok.text in RESERVED or tok.text in ("in", "do"):
                self.fail(tok, "expected the member data that takes each item after 'for'")
            names.append(self.advance().text)
            if len(names) == 2 or not self.is_op(",", self.peek()):
                break
            self.advance()
        if not self.is_word("in", self.peek()):
            self.fail(
                self.peek(),
                "expected 'in' after the loop's data",
                hint="`for x, i in xs do ... end`",
            )
        self.advance()
        at = self.peek()
        array, _ = self.expr(0)
        root = array
        while isinstance(root, Attr):
            root = root.obj
        if not isinstance(root, Name):
            self.fail(
                at,
                "'for' iterates member data (`for x in xs`), not an expression",
                hint="assign the sequence to member data first (Qt SCXML reads <foreach array> only as a location)",
            )
        if not self.is_word("do", self.peek()):
            self.fail(self.peek(), "expected 'do' after the sequence of 'for'")
        self.advance()
        actions = self.block(opening)
        closing = self.advance()
        if closing.text != "end":
            self.fail(closing, f"'{closing.text}' in a 'for' loop", hint="a loop ends with 'end'")
        self.nest -= 1
        index = names[1] if len(names) == 2 else None
        return ForEach(array=array, item=names[0], index=index, actions=actions)

    def block(self, opening: Tok) -> tuple[Action, ...]:
        """The statements of a branch, up to its `elif`, `else` or `end`."""
        found: list[Action] = []
        while True:
            while self.peek().kind == "nl" or self.is_op(";", self.peek()):
                self.advance()
            tok = self.peek()
            if tok.kind == "eof":
                where = error_at(self.text, opening.offset, "")
                self.fail(
                    tok,
                    "missing 'end'",
                    hint=f"the 'if' at line {where.line + 1}, column {where.col + 1} is never closed",
                )
            if (
                tok.kind == "word"
                and tok.text in _BRANCH_ENDS
                and not self.is_op("=", self.peek(1))
            ):
                return tuple(found)
            found.append(self.action())
            after = self.peek()
            if not self.at_end_of_statement() and not (
                after.kind == "word" and after.text in _BRANCH_ENDS
            ):
                self.unexpected(self.peek())

    def cancel(self) -> Cancel:
        self.advance()
        name = self.peek()
        if self.is_op("(", name):  # `cancel (expr)`: the send id computed
            opening = self.advance()
            computed, _ = self.expr(0)
            self.close(opening)
            return Cancel(expr=computed)
        if name.kind != "word" or name.text in RESERVED:
            self.fail(
                name,
                "expected the send id after 'cancel'",
                hint="`raise e after 1 s as t` then `cancel t`",
            )
        self.advance()
        return Cancel(sendid=name.text)

    def event_action(self) -> Raise | Send:
        verb = self.advance()
        named = self.computed_name() if verb.text == "raise" else None
        name = self.event_name(verb) if named is None else None
        content = self.content() if verb.text == "raise" else None
        args = self.arguments() if self.is_op("(", self.peek()) and content is None else ()
        if verb.text != "raise":
            assert name is not None  # only a raise computes its event's name
            after = self.peek()
            if self.is_word("after", after):
                self.fail(
                    after,
                    "only `raise` can be delayed",
                    hint="delay a `raise` to this member, and `send` from the transition it takes",
                )
            return Send(event=name, args=args)
        target = self.operand_after("to")
        via = self.operand_after("via")
        delay, sendid = None, None
        if self.is_word("after", self.peek()):
            self.advance()
            delay = self.delay()
            sendid = self.name_after("as", "a send id", "`raise e after 1 s as t`")
        into = None
        if sendid is None:  # W3C: `id` or `idlocation`, not both
            into = self.name_after("into", "a member datum", "`raise e after 1 s into d`")
        return Raise(
            event=name,
            args=args,
            delay=delay,
            sendid=sendid,
            target=target,
            via=via,
            into=into,
            named=named,
            content=content,
        )

    def computed_name(self) -> Operand | None:
        """`raise (expr)`: the event's name computed when it runs (W3C's `eventexpr`)."""
        if not self.is_op("(", self.peek()):
            return None
        opening = self.advance()
        value, _ = self.expr(0)
        self.close(opening)
        return value

    def content(self) -> Operand | None:
        """`raise e(expr)`: the event's whole data is the value (W3C's `<content>`); fields
        are `raise e(f = expr, ...)`."""
        if not self.is_op("(", self.peek()):
            return None
        named = self.peek(1).kind == "word" and self.is_op("=", self.peek(2))
        if named or self.is_op(")", self.peek(1)):
            return None  # fields (or none): `arguments`
        opening = self.advance()
        value, _ = self.expr(0)
        self.close(opening)
        return value

    def operand_after(self, word: str) -> Operand | None:
        """The expression after `word` (`to`, `via`), when `word` comes next."""
        if not self.is_word(word, self.peek()):
            return None
        self.advance()
        value, _ = self.expr(0)
        return value

    def name_after(self, word: str, what: str, hint: str) -> str | None:
        """The name after `word` (`as`, `into`), when `word` comes next."""
        if not self.is_word(word, self.peek()):
            return None
        self.advance()
        tok = self.peek()
        if tok.kind != "word" or tok.text in RESERVED:
            self.fail(tok, f"expected {what} after '{word}'", hint=hint)
        self.advance()
        return tok.text

    def event_name(self, verb: Tok) -> str:
        """The event after `raise`/`send`: a name, or W3C's dotted tokens written without blanks
        (`foo.bar`, `In-s11p112`), whatever tokens the lexer made of them."""
        first = self.peek()
        if first.kind != "word":
            self.fail(first, f"expected an event name after '{verb.text}'")
        found = EVENT_NAME.match(self.text, first.offset)
        end = found.end() if found is not None else first.offset + len(first.text)
        while self.peek().kind != "eof" and self.peek().offset < end:
            tok = self.advance()
            if tok.offset + len(tok.text) > end:  # `e-1e+5`: a number runs past the name
                self.fail(tok, f"expected an event name after '{verb.text}'")
        return self.text[first.offset : end]

    def delay(self) -> Delay:
        """`after <amount> ms|s`, or `after <amount>` with a duration string's value."""
        amount, _ = self.expr(0)
        unit: DelayUnit = ""
        tok = self.peek()
        if tok.kind == "word" and tok.text in ("ms", "s"):
            self.advance()
            unit = "ms" if tok.text == "ms" else "s"
        return Delay(amount=amount, unit=unit)

    def arguments(self) -> tuple[Arg, ...]:
        opening = self.advance()
        args: list[Arg] = []
        while not self.is_op(")", self.peek()):
            args.append(self.argument({a.name for a in args}))
            if not self.is_op(",", self.peek()):
                break
            self.advance()
        self.close(opening)
        return tuple(args)

    def argument(self, seen: set[str]) -> Arg:
        name = self.peek()
        if name.kind != "word":
            self.fail(name, f"expected an argument `name = expression`, found {_show_tok(name)}")
        if name.text in seen:
            self.fail(name, f"duplicate argument '{name.text}'")
        self.advance()
        if not self.is_op("=", self.peek()):
            self.fail(
                self.peek(),
                f"expected '=' after argument name '{name.text}'",
                hint="event arguments are written `field = expression`",
            )
        self.advance()
        value, _ = self.expr(0)
        return Arg(name=name.text, value=value)


def parse_actions(text: str) -> tuple[Action, ...]:
    """Parse an effect (or entry/exit action): statements separated by newlines or `;`."""
    parser = _StatementParser(text, statements=True)
    actions: list[Action] = []
    parser.statements_of(lambda: actions.append(parser.action()))
    return tuple(actions)
