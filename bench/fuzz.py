"""Fuzz every parser: by default 1,000,000 generated inputs shared among the targets of
`bench.fuzz_targets`, zero crashes and zero hangs expected.

Run ``.venv/bin/python -m bench.fuzz`` (a few minutes on one core), ``--inputs N`` for another
total, ``--target NAME`` (repeatable) for some targets only, ``--quick`` for the smoke test. A
failure is printed with its target and input number; ``--replay TARGET:INDEX`` runs that one
input again with the traceback. Exit status 1 if any input crashed, hung or broke an invariant.

Inputs come from a seeded ``random.Random`` per input (``--seed``, the target and the input
number), so every input is reproducible on its own: random bytes, a soup of the parser's
meaningful bytes, mutations of valid frames (bit flips, byte changes, insertions of meaningful
bytes, deletions, duplications, truncations, splices) and streams of valid frames, each fed in
a random chunking. Why not hypothesis or atheris here: atheris does not build for this Python,
and hypothesis' generation and shrinking machinery costs ~1 ms per example, a thousand times the
cost of most parsers under test; the test suite runs the same checks under hypothesis
(tests/reliability/test_fuzz_parsers.py) where shrinking matters.

Each input runs under a 1 s watchdog (``signal.setitimer``): an input still running after it is a
hang. The slowest input of each target is reported.
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import math
import random
import signal
import sys
import time
import traceback
from dataclasses import dataclass, field
from types import FrameType

from bench.fuzz_targets import TARGETS, FuzzFailureError, Target, target_named

DEFAULT_INPUTS = 1_000_000
QUICK_INPUTS_PER_TARGET = 150
HANG_BUDGET_S = 1.0


class HangError(Exception):
    """The watchdog fired: one input ran past the time budget."""


# ------------------------------------------------------------------------------------ generation


def generate(target: Target, rng: random.Random) -> bytes:
    """One input for ``target``."""
    roll = rng.random()
    if roll < 0.15:
        return rng.randbytes(rng.randint(0, target.max_size // 4))
    if roll < 0.25:
        alphabet = target.tokens + b"".join(target.seeds)
        return bytes(rng.choice(alphabet) for _ in range(rng.randint(1, target.max_size // 4)))
    stream = b"".join(rng.choice(target.seeds) for _ in range(rng.randint(1, 3)))
    if roll < 0.35:
        return stream
    data = bytearray(stream)
    for _ in range(rng.choice((1, 1, 1, 2, 2, 3, 5, 8))):
        _mutate(data, target, rng)
    return bytes(data[: target.max_size])


def _mutate(data: bytearray, target: Target, rng: random.Random) -> None:
    where = rng.randint(0, len(data))
    span = rng.randint(1, 8)
    match rng.randrange(11):
        case 0 if data:
            index = min(where, len(data) - 1)
            data[index] ^= 1 << rng.randrange(8)
        case 1 if data:
            data[min(where, len(data) - 1)] = rng.randrange(256)
        case 2 if target.tokens:
            data[where:where] = bytes((rng.choice(target.tokens),))
        case 3:
            del data[where : where + span]
        case 4:
            data[where:where] = data[where : where + span]
        case 5:
            data[where:where] = rng.randbytes(span)
        case 6:
            del data[where:]
        case 7:
            other = rng.choice(target.seeds)
            start = rng.randint(0, len(other))
            data[where:where] = other[start : start + rng.randint(1, len(other) + 1)]
        case 8 if data:
            index = min(where, len(data) - 1)
            data[index] = rng.choice((0x00, 0x7F, 0x80, 0xFF, 0x23, 0x0D, 0x0A))
        case 9:
            # Amplification: nesting, long numbers, long lines are where limits get tested.
            data[where:where] = data[where : where + span] * rng.randint(2, target.max_size // span)
        case 10 if target.tokens:
            run = rng.randint(2, target.max_size)
            data[where:where] = bytes((rng.choice(target.tokens),)) * run
        case _:
            data.append(rng.randrange(256))


def input_rng(seed: int, target_index: int, index: int) -> random.Random:
    """The generator of one input: reproducible from (seed, target, index) alone."""
    return random.Random((seed * 1_000 + target_index) * 100_000_000 + index)


# --------------------------------------------------------------------------------------- running


@dataclass
class Result:
    target: str
    inputs: int = 0
    seconds: float = 0.0
    slowest_s: float = 0.0
    slowest_index: int = -1
    slowest_rerun_s: float = 0.0
    """The slowest input timed again alone (best of 3): the first timing includes any stall of a
    shared machine."""
    problems: list[str] = field(default_factory=list)

    @property
    def rate(self) -> float:
        return self.inputs / self.seconds if self.seconds else 0.0


def _on_alarm(signum: int, frame: FrameType | None) -> None:
    raise HangError(f"still running after {HANG_BUDGET_S} s")


def run_target(target: Target, target_index: int, count: int, seed: int) -> Result:
    result = Result(target.name)
    started = time.perf_counter()
    for index in range(count):
        rng = input_rng(seed, target_index, index)
        data = generate(target, rng)
        begun = time.perf_counter()
        signal.setitimer(signal.ITIMER_REAL, HANG_BUDGET_S)
        try:
            target.check(data, rng)
        except FuzzFailureError as failure:
            result.problems.append(f"{target.name}:{index} broke an invariant: {failure}")
        except HangError as hang:
            result.problems.append(f"{target.name}:{index} hung: {hang}")
        except Exception as error:  # a crash: exactly what we are looking for
            result.problems.append(f"{target.name}:{index} crashed: {error!r}")
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
        elapsed = time.perf_counter() - begun
        if elapsed > result.slowest_s:
            result.slowest_s, result.slowest_index = elapsed, index
        result.inputs += 1
    result.seconds = time.perf_counter() - started
    result.slowest_rerun_s = rerun_time(target, target_index, result.slowest_index, seed)
    return result


def rerun_time(target: Target, target_index: int, index: int, seed: int) -> float:
    """The best of three re-runs of one input: tells a slow input from a busy machine."""
    timings = []
    for _ in range(3):
        rng = input_rng(seed, target_index, index)
        data = generate(target, rng)
        begun = time.perf_counter()
        with contextlib.suppress(Exception):
            target.check(data, rng)
        timings.append(time.perf_counter() - begun)
    return min(timings)


def replay(spec: str, seed: int) -> int:
    """Run one input (``TARGET:INDEX``) with its traceback shown."""
    name, _, index_text = spec.partition(":")
    target = target_named(name)
    target_index = TARGETS.index(target)
    rng = input_rng(seed, target_index, int(index_text))
    data = generate(target, rng)
    print(f"{name} input {index_text} ({len(data)} bytes): {data!r}")
    try:
        target.check(data, rng)
    except Exception:
        traceback.print_exc()
        return 1
    print("passes")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m bench.fuzz", description=__doc__.split("\n")[0]
    )
    parser.add_argument("--inputs", type=int, default=DEFAULT_INPUTS, help="total over targets")
    parser.add_argument("--target", action="append", help="only this target (repeatable)")
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument(
        "--quick", action="store_true", help=f"{QUICK_INPUTS_PER_TARGET} per target"
    )
    parser.add_argument("--replay", metavar="TARGET:INDEX", help="run one input, with traceback")
    args = parser.parse_args(argv)
    if args.replay:
        return replay(args.replay, args.seed)
    targets = [target_named(name) for name in args.target] if args.target else list(TARGETS)
    logging.disable(logging.WARNING)  # refusals are logged as warnings: expected, and many
    shares = sum(target.share for target in targets)
    counts = {
        target.name: QUICK_INPUTS_PER_TARGET
        if args.quick
        else max(1, math.ceil(args.inputs * target.share / shares))
        for target in targets
    }
    signal.signal(signal.SIGALRM, _on_alarm)
    print(f"fuzzing {len(targets)} targets, {sum(counts.values())} inputs, seed {args.seed}")
    print(
        f"{'target':<20}{'inputs':>10}{'seconds':>9}{'inputs/s':>10}{'slowest':>11}"
        f"{'re-run':>10}  problems"
    )
    results = []
    for target in targets:
        result = run_target(target, TARGETS.index(target), counts[target.name], args.seed)
        results.append(result)
        slowest = f"{result.slowest_s * 1000:.2f} ms"
        rerun = f"{result.slowest_rerun_s * 1000:.2f} ms"
        print(
            f"{result.target:<20}{result.inputs:>10}{result.seconds:>9.1f}{result.rate:>10.0f}"
            f"{slowest:>11}{rerun:>10}  {len(result.problems)}",
            flush=True,
        )
    inputs = sum(result.inputs for result in results)
    seconds = sum(result.seconds for result in results)
    problems = [problem for result in results for problem in result.problems]
    worst = max(results, key=lambda result: result.slowest_s)
    print(
        f"total {inputs} inputs in {seconds:.1f} s ({inputs / seconds:.0f}/s); "
        f"{len(problems)} crashes, hangs or broken invariants"
    )
    print(
        f"slowest input: {worst.target}:{worst.slowest_index} {worst.slowest_s * 1000:.2f} ms, "
        f"{worst.slowest_rerun_s * 1000:.2f} ms re-run alone (budget {HANG_BUDGET_S * 1000:.0f} ms)"
    )
    for problem in problems[:40]:
        print(problem)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
