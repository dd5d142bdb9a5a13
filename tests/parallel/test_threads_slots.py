"""Two stages sharing the cores (brdfnorm.parallel.threads: beside, Slots, run_tasks): the stage beside holds a
slot and takes freed slots first; the caller's tasks never run more than the slots allow; every task's result comes
back in the tasks' order, whichever thread ran it; a failure is raised in the stage it happened in."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

from brdfnorm.parallel import threads
from brdfnorm.parallel.threads import Slots, beside, cell_tasks, run_tasks, scope


class Meter:
    """How many tasks run at once (the largest count seen), per stage."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.running = 0
        self.most = 0
        self.by_stage: dict[str, int] = {}

    def task(self, stage: str, seconds: float = 0.01):
        def run(task: np.ndarray) -> np.ndarray:
            with self.lock:
                self.running += 1
                self.most = max(self.most, self.running)
                self.by_stage[stage] = self.by_stage.get(stage, 0) + 1
            time.sleep(seconds)
            with self.lock:
                self.running -= 1
            return task * 2

        return run


def test_stages_beside_share_the_slots_and_return_every_task_in_order():
    meter = Meter()
    tasks = cell_tasks(40, 4)

    def stage() -> list[np.ndarray]:
        return [run_tasks(meter.task("beside"), tasks, 2) for _ in range(3)]

    with scope(2), beside(stage) as averaged:
        mine = run_tasks(meter.task("caller"), tasks, 2)
        theirs = averaged()
    for result in [mine, *theirs]:
        assert [r.tolist() for r in result] == [(t * 2).tolist() for t in tasks]
    assert meter.most <= 2  # two slots: never three tasks at once (the old scheme ran three threads)
    assert meter.by_stage == {"caller": len(tasks), "beside": 3 * len(tasks)}


def test_the_stage_beside_takes_a_freed_slot_before_the_callers_tasks():
    slots = Slots(1)
    assert slots.acquire()
    order = []

    def waiter(name: str, urgent: bool) -> None:
        slots.acquire(urgent=urgent)
        order.append(name)
        slots.release()

    plain = threading.Thread(target=waiter, args=("caller", False))
    plain.start()
    time.sleep(0.05)  # (the caller's task waits first)
    urgent = threading.Thread(target=waiter, args=("beside", True))
    urgent.start()
    time.sleep(0.05)
    slots.release()
    plain.join(5)
    urgent.join(5)
    assert order == ["beside", "caller"]


def test_a_waiter_that_no_longer_wants_a_slot_gives_up():
    slots = Slots(1)
    assert slots.acquire()
    assert slots.acquire(urgent=True, wanted=lambda: False) is False


def test_a_failing_task_beside_is_raised_by_the_stage_after_its_other_tasks():
    done = []

    def task(t: np.ndarray) -> int:
        if t[0] == 1:
            raise ValueError("task 1")
        time.sleep(0.01)
        done.append(int(t[0]))
        return int(t[0])

    def stage() -> list[int]:
        return run_tasks(task, [np.array([k]) for k in range(4)], 2)

    with scope(2), beside(stage) as averaged, pytest.raises(ValueError, match="task 1"):
        averaged()
    assert 0 in done


def test_a_batch_nested_in_a_callers_task_runs_in_the_slot_the_task_holds():
    """(Were the nested batch's tasks to wait for slots of their own, the stage beside holding one and the task the
    other, they would wait forever: the tasks see no slots to take.)"""
    seen = []

    def task(t: np.ndarray) -> np.ndarray:
        seen.append(threads._SLOTS.get())
        return t

    def stage() -> list[np.ndarray]:
        return run_tasks(lambda t: t, [np.array([0])], 2)

    with scope(2), beside(stage) as averaged:
        assert threads._SLOTS.get() is not None  # (the caller's own context: its tasks take slots)
        run_tasks(task, [np.array([k]) for k in range(4)], 2)
        averaged()
    assert seen == [None] * 4
