"""Startup lists: the model, and exporters/importers for the masters people use."""

from ecattool.startup.model import TRANSITIONS, StartupCommand, StartupList

__all__ = ["TRANSITIONS", "StartupCommand", "StartupList"]
