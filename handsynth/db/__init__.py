"""handsynth.db"""
