"""Kinematics: rigid-body frames and transforms, and the 6-PSU inverse kinematics."""
