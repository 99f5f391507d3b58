"""The command queue: a fixed-capacity ring of preallocated slots (no allocation per command)."""

SLOT = 6  # keyword id + up to 5 parameters


class CommandQueue:
    """FIFO of queued commands; each slot is a list ``[keyword, p1, ..., p5]`` reused in place."""

    def __init__(self, capacity: int) -> None:
        self.capacity = capacity
        self._slots = [[0] * SLOT for _ in range(capacity)]
        self._head = 0
        self._count = 0

    def __len__(self) -> int:
        return self._count

    def push(self, keyword: int, params: list[int]) -> bool:
        """Copy a command in; False when full."""
        if self._count >= self.capacity:
            return False
        slot = self._slots[(self._head + self._count) % self.capacity]
        slot[0] = keyword
        n = len(params)
        for i in range(1, SLOT):
            slot[i] = params[i - 1] if i <= n else 0
        self._count += 1
        return True

    def pop(self) -> list[int]:
        """The oldest slot; valid until the next push (copy what you keep)."""
        slot = self._slots[self._head]
        self._head = (self._head + 1) % self.capacity
        self._count -= 1
        return slot

    def peek(self) -> "list[int] | None":
        """The oldest slot without taking it (None when empty); valid until the next push or pop."""
        return self._slots[self._head] if self._count else None

    def clear(self) -> None:
        """Empty the queue."""
        self._head = 0
        self._count = 0
