"""Touch: the finger, the worlds it moves in, and the servo logic that explores an object.

``finger`` describes the sensor layout; ``world`` is the protocol a world answers (what do
the sensors read here, and where along this move does that change?) with its shared
constants; ``sensors`` applies noise, drop-outs and false fires to any world; ``servo`` is
the paper's control cycle, which never knows which world it drives; ``stepper`` is the
analytic world; ``explorers`` is the plugin registry; ``synthetic`` samples ground-truth
contacts without exploring. The output is an :class:`tactile_kb.record.ExplorationRecord`.
"""
