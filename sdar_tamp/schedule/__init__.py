"""Asynchronous dual-arm execution of a synchronous plan (see :mod:`.scheduler`)."""

from sdar_tamp.schedule.scheduler import ORDERS, Schedule, ScheduleOptions, schedule_async

__all__ = ["ORDERS", "Schedule", "ScheduleOptions", "schedule_async"]
