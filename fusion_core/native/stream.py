"""Estimator.stream(): step() sample by sample at the C twin's speed, for a program that gets
its samples one at a time (a serial port, a ROS node, a game loop)."""

from __future__ import annotations

import struct
from typing import Any

from ..types import Estimate, InvalidSample
from .estimators import FC_SKIPPED, Stepper, has_twin
from .library import available, lib_and_ffi, reason, stream_extension

_new = tuple.__new__
_PACK6 = struct.Struct("=6d").pack_into
_UNPACK5 = struct.Struct("=5d").unpack_from
_UNPACK11 = struct.Struct("=11d").unpack_from


class Stream:
    """An estimator stepped through its C twin: `step(acc, gyro, dt)` gives what the
    estimator's own step gives, to the bit, and raises InvalidSample for the samples it
    rejects (the state unchanged); `get_state`, `set_state` and `set_param` go through the
    estimator (the twin's state copied across, exactly). Made by Estimator.stream()."""

    def __init__(self, estimator: Any) -> None:
        name = type(estimator).__name__
        if not has_twin(estimator):
            raise ValueError(f"stream(): {name} has no C twin of its own (the estimators of "
                             "fusion_core.registry have one; a subclass runs in Python)")
        if not available():
            raise ValueError(f"stream(): the C twin is unavailable ({reason()}); step() runs "
                             "the same filter in Python")
        self.estimator = estimator
        self._stepper = Stepper(estimator)
        self._position = estimator.HAS_POSITION
        _, ffi = lib_and_ffi()
        # the sample's six numbers packed at once into one buffer, acc then gyro
        self._sample = ffi.new("double[6]")
        self._sample_bytes = ffi.buffer(self._sample)
        self._acc, self._gyro = self._sample, self._sample + 3
        self._call, self._null = self._stepper._step, self._stepper._null
        self._bind()

    def _bind(self) -> None:
        """The twin's last estimate, bound for the per-sample path, and the compiled entry
        point where it is built (library.stream_extension), as this object's `step` (again
        after the stepper makes a new twin: set_state, set_param)."""
        self._last = self._stepper._last
        ext = stream_extension()
        if ext is None:
            return
        _, ffi = lib_and_ffi()
        st = self._stepper
        address = lambda cdata: int(ffi.cast("uintptr_t", cdata))  # noqa: E731
        self.step = ext.stepper(  # type: ignore[method-assign]
            address(st._step), address(st.twin), address(ffi.addressof(st.twin[0], "last")),
            self._position, Estimate, tuple.__new__, self._step_cffi, st.twin).step

    def _step_cffi(self, acc: Any, gyro: Any, dt: float) -> Estimate:
        """The compiled step's way back for the samples it does not take (not six plain
        numbers, or rejected: the cffi call says why)."""
        return Stream.step(self, acc, gyro, dt)

    def step(self, acc: Any, gyro: Any, dt: float) -> Estimate:
        """One IMU sample, as Estimator.step."""
        st = self._stepper
        try:
            _PACK6(self._sample_bytes, 0, *acc, *gyro)
            status = self._call(st.twin, self._acc, self._gyro, dt, self._null)
        except (struct.error, TypeError, ValueError, OverflowError) as err:
            raise InvalidSample(
                f"sample is not three accelerations, three rates and dt: {err}") from None
        if status > FC_SKIPPED:  # rejected, the twin's state as it was: say why
            st.sync()
            self.estimator.check_sample(acc, gyro, dt)
            raise InvalidSample("rejected by the sample rules")
        if self._position:
            v = _UNPACK11(self._last)
            return _new(Estimate, (v[0], v[1], (v[2], v[3], v[4]), (v[5], v[6], v[7]),
                                   (v[8], v[9], v[10])))
        roll, pitch, bx, by, bz = _UNPACK5(self._last)
        return _new(Estimate, (roll, pitch, (bx, by, bz), None, None))

    @property
    def last(self) -> Estimate:
        """The last estimate (as Estimator.last)."""
        self._stepper.sync()
        return self.estimator.last

    def get_state(self) -> dict[str, Any]:
        """Estimator.get_state of the state the twin holds."""
        self._stepper.sync()
        return self.estimator.get_state()

    def set_state(self, snapshot: dict[str, Any]) -> None:
        """Estimator.set_state, then the twin continues from it."""
        self.estimator.set_state(snapshot)
        self._stepper.load()
        self._bind()

    def set_param(self, name: str, value: Any) -> None:
        """Estimator.set_param, the state kept."""
        self._stepper.sync()
        self.estimator.set_param(name, value)
        self._stepper.load()
        self._bind()
