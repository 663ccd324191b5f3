"""Asynchronous execution of a synchronous plan: its steps re-timed per arm (:mod:`.scheduler`)
or one timeline per arm by prioritised planning in time (:mod:`.timelines`)."""

from sdar_tamp.schedule.scheduler import ORDERS, Schedule, ScheduleOptions, schedule_async

__all__ = ["ORDERS", "Schedule", "ScheduleOptions", "schedule_async"]
