"""BehaviorTree.CPP's script language: lexer, parser and evaluator.

Used by ``Script``, ``ScriptCondition``, ``Precondition`` and the ``_skipIf``/``_onSuccess``...
attributes. A script is a list of expressions separated by ``;``; its value is the value of the
last one. Supported, with BT.CPP's precedence (lowest first):

- assignment ``:=`` (create or overwrite), ``=`` (the entry must exist), ``+= -= *= /=``
- conditional ``c ? a : b``
- logical ``&&`` and ``||`` (same precedence, left to right, both sides evaluated)
- comparisons ``== != < <= > >=`` (chainable: ``1 < x < 3``)
- string concatenation ``..``; bitwise ``| ^`` and ``&``
- ``+ -``; ``* /``; prefix ``-``, ``!``, ``~``
- atoms: numbers (``42``, ``3.5``, ``0x1F``), single- or double-quoted strings, ``true`` and
  ``false``, blackboard names (``@name`` is the root blackboard), parentheses.

Syntax errors are :class:`ScriptSyntaxError` with the 1-based column; run-time errors (unknown
variable, bad operand types) are :class:`ScriptRuntimeError`.
"""

from __future__ import annotations

import math
import re
import sys
from dataclasses import dataclass
from functools import lru_cache
from types import FrameType
from typing import Any, Protocol, TypeGuard, cast

FLOAT_EPS = 1.1920928955078125e-07  # float epsilon, the tolerance BT.CPP uses for ==


class ScriptSyntaxError(ValueError):
    """A script does not parse; ``column`` is 1-based within the script text."""

    def __init__(self, message: str, column: int) -> None:
        super().__init__(message)
        self.message = message
        self.column = column


class ScriptRuntimeError(RuntimeError):
    """A script parsed but failed while running (unknown variable, bad operand types...)."""


class Variables(Protocol):
    def exists(self, key: str) -> bool: ...
    def get(self, key: str) -> Any: ...
    def set(self, key: str, value: Any) -> None: ...


# ---------------------------------------------------------------------------------------------
# Lexer

_OPERATORS = sorted(
    [":=", "+=", "-=", "*=", "/=", "==", "!=", "<=", ">=", "&&", "||", "..",
     "=", "<", ">", "&", "|", "^", "~", "!", "+", "-", "*", "/", "?", ":", "(", ")", ";"],
    key=len,
    reverse=True,
)
_OPERATOR = re.compile("|".join(re.escape(op) for op in _OPERATORS))
"""The longest operator at a position (the alternatives are tried longest first)."""


@dataclass(frozen=True)
class Token:
    kind: str  # "num", "str", "name", "bool", "op", "end"
    text: str
    value: Any
    pos: int  # 0-based offset in the script


def tokenize(code: str) -> list[Token]:
    tokens: list[Token] = []
    i, n = 0, len(code)
    while i < n:
        c = code[i]
        if c in " \t\r\n":
            i += 1
            continue
        if c.isdigit() or (c == "." and i + 1 < n and code[i + 1].isdigit()):
            tokens.append(_number(code, i))
            i += len(tokens[-1].text)
            continue
        if c in "'\"":
            end = code.find(c, i + 1)
            if end < 0:
                raise ScriptSyntaxError("unterminated string; close it with " + c, i + 1)
            tokens.append(Token("str", code[i : end + 1], code[i + 1 : end], i))
            i = end + 1
            continue
        if c.isalpha() or c in "_@":
            j = i + 1
            while j < n and (code[j].isalnum() or code[j] == "_"):
                j += 1
            word = code[i:j]
            if word == "@":
                raise ScriptSyntaxError("'@' must be followed by a variable name", i + 1)
            if word in ("true", "false"):
                tokens.append(Token("bool", word, word == "true", i))
            else:
                tokens.append(Token("name", word, word, i))
            i = j
            continue
        match = _OPERATOR.match(code, i)
        if match is None:
            raise ScriptSyntaxError(f"unexpected character '{c}'", i + 1)
        op = match.group()
        tokens.append(Token("op", op, op, i))
        i += len(op)
    tokens.append(Token("end", "", None, n))
    return tokens


def _number(code: str, i: int) -> Token:
    n = len(code)
    if code.startswith(("0x", "0X"), i):
        j = i + 2
        while j < n and code[j] in "0123456789abcdefABCDEF":
            j += 1
        if j == i + 2:
            raise ScriptSyntaxError("hexadecimal number without digits", i + 1)
        return Token("num", code[i:j], int(code[i + 2 : j], 16), i)
    j = i
    while j < n and code[j].isdigit():
        j += 1
    is_real = False
    if j < n and code[j] == "." and j + 1 < n and code[j + 1].isdigit():
        is_real = True
        j += 1
        while j < n and code[j].isdigit():
            j += 1
    if j < n and code[j] in "eE":
        k = j + 1
        if k < n and code[k] in "+-":
            k += 1
        if k < n and code[k].isdigit():
            is_real = True
            j = k
            while j < n and code[j].isdigit():
                j += 1
    if j < n and (code[j].isalpha() or code[j] == "_"):
        raise ScriptSyntaxError(f"malformed number '{code[i:j + 1]}'", i + 1)
    text = code[i:j]
    return Token("num", text, float(text) if is_real else int(text), i)


# ---------------------------------------------------------------------------------------------
# AST


class Expr:
    pos: int = 0

    def eval(self, env: Variables) -> Any:
        raise NotImplementedError


@dataclass
class Constant(Expr):
    value: Any
    pos: int = 0

    def eval(self, env: Variables) -> Any:
        return self.value


@dataclass
class Name(Expr):
    name: str
    pos: int = 0

    def eval(self, env: Variables) -> Any:
        try:
            return env.get(self.name)
        except KeyError:
            raise ScriptRuntimeError(f"variable not found: {self.name}") from None


@dataclass
class Unary(Expr):
    op: str
    operand: Expr
    pos: int = 0

    def eval(self, env: Variables) -> Any:
        v = self.operand.eval(env)
        if self.op == "!":
            if isinstance(v, str):
                raise ScriptRuntimeError("operator [!] cannot be used with a string")
            return not to_number(v, "!")
        num = to_number(v, self.op)
        if self.op == "-":
            return -float(num)
        return float(~int(num)) if isinstance(num, float) else ~int(num)


@dataclass
class Binary(Expr):
    op: str
    lhs: Expr
    rhs: Expr
    pos: int = 0

    def eval(self, env: Variables) -> Any:
        return binary(self.op, self.lhs.eval(env), self.rhs.eval(env))


@dataclass
class Compare(Expr):
    ops: list[str]
    operands: list[Expr]
    pos: int = 0

    def eval(self, env: Variables) -> Any:
        lhs = self.operands[0].eval(env)
        for op, operand in zip(self.ops, self.operands[1:], strict=True):
            rhs = operand.eval(env)
            if not compare(op, lhs, rhs):
                return False
            lhs = rhs
        return True


@dataclass
class IfElse(Expr):
    cond: Expr
    then: Expr
    other: Expr
    pos: int = 0

    def eval(self, env: Variables) -> Any:
        c = self.cond.eval(env)
        ok = bool(to_number(c, "?"))
        return self.then.eval(env) if ok else self.other.eval(env)


@dataclass
class Assign(Expr):
    """``name := value``, ``name = value`` and ``name += value`` (and ``-= *= /=``).

    As in BT.CPP, an entry keeps its type: text assigned to a number entry is converted to a
    number, a number assigned to a text entry is an error, a non-integral number assigned to an
    integer entry is an error; ``+= -= *= /=`` with a number need a number entry, and ``+=``
    with text needs a text entry.
    """

    op: str
    target: str
    value: Expr
    pos: int = 0

    def eval(self, env: Variables) -> Any:
        key = self.target
        if not env.exists(key) and self.op != ":=":
            raise ScriptRuntimeError(
                f"the blackboard entry [{key}] does not exist yet; use := to create it"
            )
        value = self.value.eval(env)
        has_value = getattr(env, "has_value", env.exists)(key)
        if self.op in (":=", "="):
            if has_value:
                value = _convert_for(key, env.get(key), value)
            _store(env, key, value)
            return value
        if not has_value:
            raise ScriptRuntimeError(f"the entry [{key}] has no value to use with {self.op}")
        old = env.get(key)
        if isinstance(value, str):
            if self.op != "+=":
                raise ScriptRuntimeError(f"operator {self.op} cannot be used with strings")
            if not isinstance(old, str):
                raise ScriptRuntimeError(
                    f"{self.op} with a string cannot be used on entry [{key}], which holds "
                    f"a {_type_label(old)}")
            new: Any = old + value
        else:
            if not _is_number(old) and not isinstance(old, bool):
                raise ScriptRuntimeError(
                    f"operator {self.op} cannot be used on entry [{key}], which holds a "
                    f"{_type_label(old)} (not a number)")
            new = binary(self.op[0], to_number(old, self.op), to_number(value, self.op))
            new = _convert_for(key, old, new)
        _store(env, key, new)
        return new


def _store(env: Variables, key: str, value: Any) -> None:
    try:
        getattr(env, "assign", env.set)(key, value)
    except ValueError as e:  # the entry's type cannot hold the value
        raise ScriptRuntimeError(str(e)) from None


def _type_label(value: Any) -> str:
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int):
        return "int"
    if isinstance(value, float):
        return "double"
    if isinstance(value, str):
        return "string"
    return type(value).__name__


def _convert_for(key: str, old: Any, value: Any) -> Any:
    """``value`` as it can be stored in entry ``key`` holding ``old`` (BT.CPP's rules)."""
    if isinstance(value, str):
        if isinstance(old, str):
            return value
        if _is_number(old) or isinstance(old, bool):
            return _string_to_number(value)
        from_string = getattr(type(old), "from_string", None)
        if callable(from_string):
            return from_string(value)
        raise ScriptRuntimeError(
            f"cannot assign a string to entry [{key}], which holds a {_type_label(old)}")
    if isinstance(old, str) and value is not None:
        raise ScriptRuntimeError(
            f"cannot assign a {_type_label(value)} to entry [{key}], which holds a string")
    if type(old) is float and type(value) is int:  # a double entry stays double
        return float(value)
    if type(old) in (int, bool) and type(value) is float:
        if not value.is_integer():
            raise ScriptRuntimeError(
                f"cannot assign {value} to entry [{key}], which holds a {_type_label(old)}")
        return int(value)
    return value


@dataclass(frozen=True)
class Script:
    """A parsed script: call :meth:`run` with the blackboard to execute it. Running it changes
    nothing in it, so the nodes of every script of the same text share one
    (:func:`parse_script` keeps them)."""

    code: str
    statements: tuple[Expr, ...]

    def run(self, env: Variables) -> Any:
        result: Any = None
        for statement in self.statements:
            result = statement.eval(env)
        return result

    def run_bool(self, env: Variables) -> bool:
        return to_bool(self.run(env))


# ---------------------------------------------------------------------------------------------
# Value semantics


def _is_number(v: Any) -> TypeGuard[int | float]:
    return isinstance(v, (int, float)) and not isinstance(v, str)


def _string_to_number(s: str) -> int | float:
    text = s.strip()
    if text == "true":
        return 1
    if text == "false":
        return 0
    try:
        return int(text, 0) if text.lower().startswith("0x") else int(text)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        raise ScriptRuntimeError(f"'{s}' is not a number") from None


def to_number(v: Any, op: str) -> int | float:
    if isinstance(v, bool):
        return int(v)
    if _is_number(v):
        return v
    if isinstance(v, str):
        return _string_to_number(v)
    raise ScriptRuntimeError(f"operator [{op}] needs a number, got {type(v).__name__}")


def to_bool(v: Any) -> bool:
    """BT.CPP's cast to bool (a condition's value): a bool, the integers 0 and 1, or a
    non-negative real (true when non-zero). Other integers, negative numbers and strings (even
    'true') are errors, as in BT.CPP."""
    if isinstance(v, bool):
        return v
    if isinstance(v, int):
        if v < 0:
            raise ScriptRuntimeError(f"{v} is negative and cannot be converted to a boolean")
        if v > 1:
            raise ScriptRuntimeError(
                f"{v} cannot be converted to a boolean (only 0 and 1 can; compare it instead)")
        return v == 1
    if isinstance(v, float):
        if v < 0:
            raise ScriptRuntimeError(f"{v} is negative and cannot be converted to a boolean")
        return v != 0
    if isinstance(v, str):
        raise ScriptRuntimeError(
            f"the string '{v}' cannot be converted to a boolean (compare it instead)")
    if v is None:
        raise ScriptRuntimeError("the script has no value to use as a condition")
    raise ScriptRuntimeError(f"cannot convert {type(v).__name__} to a boolean")


def to_text(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float) and v.is_integer() and math.isfinite(v):
        return str(int(v))
    return str(v)


def concat_text(v: Any) -> str:
    """Text of a value for ``..``, as BT.CPP converts it: ``true`` is "1", a real is written
    with six decimals (``1 + 2`` gives "3.000000", ``2.5`` "2.500000"), an integer as is."""
    if isinstance(v, bool):
        return "1" if v else "0"
    if isinstance(v, float):
        if math.isfinite(v):
            return f"{v:f}"
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf")
    return to_text(v)


def _arith(op: str, a: int | float, b: int | float) -> float:
    """BT.CPP computes in double: ``1 + 2`` is 3.0 (stored as 3 into an int entry)."""
    a = float(a)
    b = float(b)
    if op == "+":
        return a + b
    if op == "-":
        return a - b
    if op == "*":
        return a * b
    if b == 0:
        if a == 0:
            return math.nan
        return math.copysign(math.inf, a) * math.copysign(1.0, b)
    return a / b


def binary(op: str, lhs: Any, rhs: Any) -> Any:
    if op in ("&&", "||"):
        if isinstance(lhs, str) or isinstance(rhs, str):
            raise ScriptRuntimeError(f"operation [{op}] is not permitted with strings")
        try:
            a, b = to_bool(lhs), to_bool(rhs)
        except ScriptRuntimeError as e:
            raise ScriptRuntimeError(f"operator [{op}] needs operands that are booleans: {e}"
                                     ) from None
        return (a and b) if op == "&&" else (a or b)
    if op == "..":
        return concat_text(lhs) + concat_text(rhs)
    if op == "+" and isinstance(lhs, str) and isinstance(rhs, str):
        return lhs + rhs
    if isinstance(lhs, str) or isinstance(rhs, str):
        raise ScriptRuntimeError(f"operation [{op}] is not permitted between {lhs!r} and {rhs!r}")
    x, y = to_number(lhs, op), to_number(rhs, op)
    if op in ("&", "|", "^"):
        if float(x) != int(x) or float(y) != int(y):
            raise ScriptRuntimeError(f"bitwise operator [{op}] needs integers")
        ia, ib = int(x), int(y)
        return ia & ib if op == "&" else (ia | ib if op == "|" else ia ^ ib)
    return _arith(op, x, y)


def compare(op: str, lhs: Any, rhs: Any) -> bool:
    if isinstance(lhs, str) and isinstance(rhs, str):
        a: Any = lhs
        b: Any = rhs
        eq: bool = a == b
    else:
        a = to_number(lhs, op)
        b = to_number(rhs, op)
        eq = abs(a - b) <= FLOAT_EPS
    if op == "==":
        return eq
    if op == "!=":
        return not eq
    # two strs or two numbers: the comparison gives a bool
    if op == "<":
        return cast(bool, a < b)
    if op == ">":
        return cast(bool, a > b)
    if op == "<=":
        return cast(bool, a <= b)
    return cast(bool, a >= b)


# ---------------------------------------------------------------------------------------------
# Parser

_ASSIGN_OPS = (":=", "=", "+=", "-=", "*=", "/=")
_COMPARE_OPS = ("==", "!=", "<", "<=", ">", ">=")


class _Parser:
    def __init__(self, code: str) -> None:
        self.code = code
        self.tokens = tokenize(code)
        self.i = 0

    @property
    def tok(self) -> Token:
        return self.tokens[self.i]

    def error(self, message: str, tok: Token | None = None) -> ScriptSyntaxError:
        t = tok or self.tok
        found = "end of script" if t.kind == "end" else f"'{t.text}'"
        return ScriptSyntaxError(f"{message}, found {found}", t.pos + 1)

    def accept(self, *ops: str) -> Token | None:
        t = self.tok
        if t.kind == "op" and t.text in ops:
            self.i += 1
            return t
        return None

    def parse(self) -> list[Expr]:
        statements: list[Expr] = []
        while self.tok.kind != "end":
            if self.accept(";"):
                continue
            statements.append(self.expression())
            if self.tok.kind != "end" and not self.accept(";"):
                raise self.error("expected ';' or an operator")
        return statements

    def expression(self) -> Expr:
        start = self.tok
        lhs = self.conditional()
        op = self.accept(*_ASSIGN_OPS)
        if op is None:
            return lhs
        if not isinstance(lhs, Name):
            raise ScriptSyntaxError(
                f"the left side of '{op.text}' must be a variable name", start.pos + 1
            )
        return Assign(op.text, lhs.name, self.expression(), op.pos)

    def conditional(self) -> Expr:
        cond = self.logical()
        q = self.accept("?")
        if q is None:
            return cond
        then = self.expression()
        if not self.accept(":"):
            raise self.error("expected ':' after the '?' branch")
        other = self.logical()
        return IfElse(cond, then, other, q.pos)

    def logical(self) -> Expr:
        lhs = self.comparison()
        while (op := self.accept("&&", "||")) is not None:
            lhs = Binary(op.text, lhs, self.comparison(), op.pos)
        return lhs

    def comparison(self) -> Expr:
        first = self.concat()
        ops: list[str] = []
        operands = [first]
        while (op := self.accept(*_COMPARE_OPS)) is not None:
            ops.append(op.text)
            operands.append(self.concat())
        return first if not ops else Compare(ops, operands, first.pos)

    def concat(self) -> Expr:
        lhs = self.bit_or()
        while (op := self.accept("..")) is not None:
            lhs = Binary("..", lhs, self.bit_or(), op.pos)
        return lhs

    def bit_or(self) -> Expr:
        lhs = self.bit_and()
        while (op := self.accept("|", "^")) is not None:
            lhs = Binary(op.text, lhs, self.bit_and(), op.pos)
        return lhs

    def bit_and(self) -> Expr:
        lhs = self.sum()
        while (op := self.accept("&")) is not None:
            lhs = Binary("&", lhs, self.sum(), op.pos)
        return lhs

    def sum(self) -> Expr:
        lhs = self.product()
        while (op := self.accept("+", "-")) is not None:
            lhs = Binary(op.text, lhs, self.product(), op.pos)
        return lhs

    def product(self) -> Expr:
        lhs = self.unary()
        while (op := self.accept("*", "/")) is not None:
            lhs = Binary(op.text, lhs, self.unary(), op.pos)
        return lhs

    def unary(self) -> Expr:
        op = self.accept("-", "!", "~")
        if op is not None:
            return Unary(op.text, self.unary(), op.pos)
        return self.atom()

    def atom(self) -> Expr:
        t = self.tok
        if t.kind in ("num", "str", "bool"):
            self.i += 1
            return Constant(t.value, t.pos)
        if t.kind == "name":
            self.i += 1
            return Name(t.value, t.pos)
        if self.accept("("):
            inner = self.expression()
            if not self.accept(")"):
                raise self.error("expected ')'")
            return inner
        raise self.error("expected a value (number, 'string', true/false, name or '(')")


MAX_SCRIPT_DEPTH = 100
"""Expressions nested in expressions (parentheses, operators, operands): at most this deep."""
MAX_SCRIPT_CHARS = 20_000
"""Characters of one script: at most this many (parsing takes several microseconds each)."""
PARSED_KEPT = 4096
"""Parsed scripts kept by :func:`parse_script` for texts met again."""


def parse_script(code: str) -> Script:
    """Parse ``code``; raises :class:`ScriptSyntaxError` (with column) when it is not valid.

    A script longer than :data:`MAX_SCRIPT_CHARS` or nested deeper than
    :data:`MAX_SCRIPT_DEPTH` is refused, so that neither parsing nor running it can take long
    or exhaust Python's stack. The last :data:`PARSED_KEPT` scripts parsed are kept: a text
    met again (the same script in every instance of a SubTree, checked then built) is not
    parsed again.
    """
    if len(code) > MAX_SCRIPT_CHARS:
        raise ScriptSyntaxError(f"script of {len(code):,} characters, more than the limit of "
                                f"{MAX_SCRIPT_CHARS:,}; split it into several scripts", 1)
    return _parsed(code)


@lru_cache(maxsize=PARSED_KEPT)
def _parsed(code: str) -> Script:
    try:
        statements = _parse_in_budget(code)
    except RecursionError:
        raise ScriptSyntaxError("expression nested too deeply to parse (parentheses or "
                                "operators); split it into several statements", 1) from None
    if any(_depth(statement) > MAX_SCRIPT_DEPTH for statement in statements):
        raise ScriptSyntaxError(f"expression nested deeper than {MAX_SCRIPT_DEPTH} levels; "
                                "split it into several statements", 1)
    return Script(code, tuple(statements))


PARSE_FRAMES = 4000
"""Python frames the parser may use, whatever the process did before (so a script is accepted
or refused the same way in every process)."""


def _parse_in_budget(code: str) -> list[Expr]:
    depth = 0
    frame: FrameType | None = sys._getframe()
    while frame is not None:
        depth, frame = depth + 1, frame.f_back
    old = sys.getrecursionlimit()
    sys.setrecursionlimit(depth + PARSE_FRAMES)
    try:
        return _Parser(code).parse()
    finally:
        sys.setrecursionlimit(old)


def _depth(root: Expr) -> int:
    """Nesting depth of an expression tree, measured without recursion."""
    best = 0
    stack: list[tuple[Any, int]] = [(root, 1)]
    while stack:
        node, level = stack.pop()
        best = max(best, level)
        for value in vars(node).values():
            items = value if isinstance(value, list) else [value]
            stack.extend((item, level + 1) for item in items if isinstance(item, Expr))
    return best


def run_script(code: str, env: Variables) -> Any:
    return parse_script(code).run(env)
