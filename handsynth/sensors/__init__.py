"""handsynth.sensors"""
