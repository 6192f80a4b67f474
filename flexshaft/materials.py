"""Linear elastic isotropic materials, SI units."""

from __future__ import annotations

from dataclasses import dataclass

from .validation import check_real

__all__ = ["Material", "STEEL", "BUILTIN_MATERIALS"]


@dataclass(frozen=True)
class Material:
    """An isotropic linear elastic material.

    Parameters
    ----------
    E : float
        Young's modulus, Pa.
    nu : float
        Poisson's ratio, dimensionless, in (-1, 0.5).
    rho : float
        Density, kg/m³.
    name : str
        A label for reports and exports.
    """

    E: float
    nu: float
    rho: float
    name: str = "material"

    def __post_init__(self) -> None:
        object.__setattr__(self, "E", check_real(self.E, "E", "Pa", lo=0.0, lo_open=True))
        # nu = 0.5 would make the material incompressible and G = E/3 still fine,
        # but bulk modulus infinite; solid FE later needs nu < 0.5.
        object.__setattr__(
            self, "nu", check_real(self.nu, "nu", "", lo=-1.0, lo_open=True, hi=0.5, hi_open=True)
        )
        object.__setattr__(self, "rho", check_real(self.rho, "rho", "kg/m³", lo=0.0, lo_open=True))

    @property
    def G(self) -> float:
        """Shear modulus G = E / (2 (1 + nu)), Pa."""
        return self.E / (2.0 * (1.0 + self.nu))


#: Structural steel as the study used it (E = 210 GPa, nu = 0.29, rho = 7850 kg/m³).
STEEL = Material(E=210e9, nu=0.29, rho=7850.0, name="steel")

BUILTIN_MATERIALS: dict[str, Material] = {"steel": STEEL}
