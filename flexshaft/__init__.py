"""flexshaft: drivetrain shafts from CAD to validated flexible-body dynamics.

The public API in one place; heavy dependencies load only where needed.
"""

from .assembly import AssembledModel, Station, assemble
from .components import Coupling, Drivetrain, Rayleigh, Reduce, Rigid, Shaft
from .damping import modal_damping_matrix, rayleigh_coefficients, rayleigh_ratio
from .errors import ModelError
from .materials import STEEL, Material
from .modal import ModalResult, modal_analysis
from .modelfile import load_model, loads_model
from .reduction import FlexibleBody, ModalDamping, cb_check, craig_bampton, select_modes

__version__ = "0.1.0"

__all__ = [
    "AssembledModel",
    "Coupling",
    "Drivetrain",
    "FlexibleBody",
    "Material",
    "ModalDamping",
    "ModalResult",
    "ModelError",
    "Rayleigh",
    "Reduce",
    "Rigid",
    "STEEL",
    "Shaft",
    "Station",
    "assemble",
    "cb_check",
    "craig_bampton",
    "load_model",
    "loads_model",
    "modal_analysis",
    "modal_damping_matrix",
    "rayleigh_coefficients",
    "rayleigh_ratio",
    "select_modes",
]
