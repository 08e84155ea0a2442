"""Physics at the hand: actuators and transmissions (``actuator``), the paper's 2-DOF
haptic model (``model``, its metrics; on its transfer functions ``impedance``, its bandwidth
``bandwidth`` and the limits of the rendered spring ``limits``), the cheaper stand-ins for
its exact delay (``delay``), the Z-width (``zwidth``) and the sampled-data passivity
(``sampled``), and the backdrive force in free motion (``hand``, with the coupled
stability).

Layer: imports ``geometry.validation`` only; the application (``mrclutch``) and the
presentation (``mrclutch.cli``) import it, never the other way round.
"""
