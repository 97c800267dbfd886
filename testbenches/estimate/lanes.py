"""How `imu-fusion estimate` runs its tasks over a recording's blocks: each task (an
estimator's run, VQF's) at its own pace on as many threads as the machine has cores, the next
block read while they work, memory bounded by the blocks held at once."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

IN_FLIGHT = 2
"""Blocks read ahead of the slowest task at most: what bounds memory while each task works
through the blocks at its own pace (Lanes)."""


class Lanes:
    """Every task (an estimator's or VQF's run) takes the blocks in order, each at its own pace:
    no task waits for the others at the end of a block. As many worker threads as the machine
    has cores take whichever task has a block waiting and is not running (the C twins run
    without the GIL, so the cores stay busy; one thread per task would hold a malloc arena and
    a block's outputs each). Blocks are handed out as read, at most IN_FLIGHT held at once
    (submit waits); `done(n)` is called once every task has finished a block of n rows. The
    first exception of a task is raised by submit or close."""

    def __init__(self, tasks: list[Any], done: Callable[[int], None]) -> None:
        import collections
        import os
        import queue
        import threading

        self._done, self._lock = done, threading.Lock()
        self._idle = threading.Condition(self._lock)  # notified when no block is left
        self._slots = threading.Semaphore(IN_FLIGHT)
        self._left: dict[int, list[int]] = {}  # block id -> [tasks still on it, rows]
        self._error: BaseException | None = None
        self._pending: list[collections.deque[Any]] = [collections.deque() for _ in tasks]
        self._busy = [False] * len(tasks)  # running, or waiting in the ready queue
        self._tasks = tasks
        self._ready: queue.Queue[int | None] = queue.Queue()
        self._next = 0
        self._workers = [threading.Thread(target=self._work, daemon=True)
                         for _ in range(max(1, min(len(tasks), os.cpu_count() or 1)))]
        for worker in self._workers:
            worker.start()

    def _work(self) -> None:
        while (i := self._ready.get()) is not None:
            with self._lock:
                block_id, args = self._pending[i].popleft()
            if self._error is None:
                try:
                    self._tasks[i].block(*args)
                except BaseException as err:  # raised in the caller
                    with self._lock:
                        self._error = self._error or err
            del args  # a worker holds no block between tasks
            with self._lock:
                if self._pending[i]:
                    self._ready.put(i)  # its next block
                else:
                    self._busy[i] = False
            self._finished(block_id)

    def _finished(self, block_id: int) -> None:
        with self._lock:
            left = self._left[block_id]
            left[0] -= 1
            if left[0] > 0:
                return
            del self._left[block_id]
            if not self._left:
                self._idle.notify_all()
        self._slots.release()
        if self._error is None:
            self._done(left[1])

    def submit(self, rows: int, *args: Any) -> None:
        """One block (rows long) to every task: task.block(*args)."""
        self._slots.acquire()
        self._raise()
        with self._lock:
            self._left[self._next] = [len(self._tasks), rows]
            for i, pending in enumerate(self._pending):
                pending.append((self._next, args))
                if not self._busy[i]:
                    self._busy[i] = True
                    self._ready.put(i)
        self._next += 1

    def close(self, quiet: bool = False) -> None:
        """Wait for every task to finish its blocks; raise the first exception of any (quiet:
        none, the caller is raising its own)."""
        if quiet:
            with self._lock:
                self._error = self._error or RuntimeError("stopped")  # the rest is skipped
        with self._idle:  # every block done (the workers put tasks' next blocks in the queue)
            while self._left:
                self._idle.wait()
        for _ in self._workers:
            self._ready.put(None)
        for worker in self._workers:
            worker.join()
        if not quiet:
            self._raise()

    def _raise(self) -> None:
        if self._error is not None:
            raise self._error


def read_ahead(blocks: Any) -> Any:
    """The blocks of an iterator, the next one read by a thread of its own while the caller
    works on the last (the reader's exceptions raised in the caller, in order); the thread has
    ended when the caller's loop does, however it ends."""
    import queue
    import threading

    ready: queue.Queue[Any] = queue.Queue(maxsize=1)
    stop = threading.Event()

    def read() -> None:
        try:
            for block in blocks:
                while not stop.is_set():
                    try:
                        ready.put((block, None), timeout=0.1)
                        break
                    except queue.Full:
                        continue
                if stop.is_set():
                    return
            ready.put((None, None))
        except BaseException as err:  # handed to the caller
            ready.put((None, err))

    thread = threading.Thread(target=read, daemon=True)
    thread.start()
    try:
        while True:
            block, err = ready.get()
            if err is not None:
                raise err
            if block is None:
                return
            yield block
    finally:  # the reader stops after its block in hand: no read is left running at exit,
        stop.set()  # where a C++ reader's threads torn down mid-read abort the process
        thread.join()
