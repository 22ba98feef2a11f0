"""handsynth.estimate"""
