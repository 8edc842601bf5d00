"""Act: grasping by the minimal angle of prehension.

``quality`` holds the grasp metrics (Nguyen's force closure, the soft-finger Ferrari–Canny ε,
the least holding force); ``planner`` pairs parallel faces in line with the centre of mass.
"""
