"""Counts in words, for messages: `count(1, "dropout")` is "1 dropout", `count(3, "dropout")`
"3 dropouts"."""


def count(n: int, word: str, plural: str | None = None) -> str:
    """`n` and `word`, in the plural (`plural`, or `word + "s"`) unless `n` is 1."""
    return f"{n} {word if n == 1 else (plural or word + 's')}"
