"""Constraint families of the constrained DMP fit; each emits linear rows on the weights."""

from tooltransfer.dmp.qp.constraints.base import Coefficients, Constraint, Rows
from tooltransfer.dmp.qp.constraints.cone import VelocityCone, cone_rows
from tooltransfer.dmp.qp.constraints.disc import OutsideDisc
from tooltransfer.dmp.qp.constraints.endpoint import FixedEndPoint, ZeroEndVelocity
from tooltransfer.dmp.qp.constraints.outside_polygon import OutsidePolygon
from tooltransfer.dmp.qp.constraints.polygon import PositionPolygon

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
    "cone_rows",
]
