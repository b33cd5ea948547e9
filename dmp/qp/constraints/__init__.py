"""Constraint families of the constrained DMP fit; each emits linear rows on the weights."""

from dmp.qp.constraints.base import Coefficients, Constraint, Rows
from dmp.qp.constraints.cone import VelocityCone
from dmp.qp.constraints.disc import OutsideDisc
from dmp.qp.constraints.endpoint import FixedEndPoint, ZeroEndVelocity
from dmp.qp.constraints.outside_polygon import OutsidePolygon
from dmp.qp.constraints.polygon import PositionPolygon

__all__ = [
    "Coefficients",
    "Constraint",
    "FixedEndPoint",
    "OutsideDisc",
    "OutsidePolygon",
    "PositionPolygon",
    "Rows",
    "VelocityCone",
    "ZeroEndVelocity",
]
