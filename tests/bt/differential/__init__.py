"""Differential testing of bt-manip against the real BehaviorTree.CPP 4.8.2."""
