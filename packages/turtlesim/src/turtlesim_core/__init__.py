"""turtlesim's simulation, independent of any transport: the world and its turtles
(``world``), the pen-drawn raster (``canvas``), the PNG encoder (``png``) and the optional Tk
window (``gui``). The ``turtlesim_node`` script wires these to topics and services."""
