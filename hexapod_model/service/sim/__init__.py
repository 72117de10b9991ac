"""Simulated encoders: poses played to CAN frames of the fixtures' own layouts, with injected faults."""

from .config import Fault, SimConfig, SimFixture, load_simulation, simulation_from_dict
from .simulator import SentSet, Simulator

__all__ = ["Fault", "SentSet", "SimConfig", "SimFixture", "Simulator", "load_simulation", "simulation_from_dict"]
