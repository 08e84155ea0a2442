"""Physics at the hand: actuators and transmissions (``actuator``), the paper's 2-DOF
haptic model (``model``) and the cheaper stand-ins for its exact delay (``delay``).

Layer: imports ``geometry.validation`` only; the application (``mrclutch``) and the
presentation (``mrclutch.cli``) import it, never the other way round.
"""
