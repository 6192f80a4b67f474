"""Linear elastic isotropic materials, SI units."""

from __future__ import annotations

from dataclasses import dataclass

from ..validation import check_real

__all__ = ["Material", "STEEL", "BUILTIN_MATERIALS", "E_RANGE_PA", "RHO_MAX"]

#: Young's moduli accepted, Pa: from a soft foam (1 kPa) to a thousand times diamond's (1.2e12 Pa).
#: Past them a part's frequencies leave what the solvers resolve (E = 1e-10 Pa: modes of 1e-8 rad/s,
#: which the Campbell diagram took for rigid-body ones) or its element matrices overflow (1e308 Pa).
E_RANGE_PA = (1e3, 1e15)
#: Largest density accepted, kg/m³: 40 times osmium's (22 600 kg/m³); 1e20 kg/m³ left the same
#: unresolvable frequencies. There is no floor: a part may be nearly massless.
RHO_MAX = 1e6


@dataclass(frozen=True)
class Material:
    """An isotropic linear elastic material.

    Parameters
    ----------
    E : float
        Young's modulus, Pa, in :data:`E_RANGE_PA` (1e3 to 1e15).
    nu : float
        Poisson's ratio, dimensionless, in (-1, 0.5).
    rho : float
        Density, kg/m³, > 0 and at most :data:`RHO_MAX` (1e6).
    name : str
        A label for reports and exports.
    """

    E: float
    nu: float
    rho: float
    name: str = "material"

    def __post_init__(self) -> None:
        object.__setattr__(self, "E", check_real(self.E, "E", "Pa", lo=E_RANGE_PA[0], hi=E_RANGE_PA[1]))
        # nu = 0.5 would make the material incompressible and G = E/3 still fine,
        # but bulk modulus infinite; solid FE later needs nu < 0.5.
        object.__setattr__(
            self, "nu", check_real(self.nu, "nu", "", lo=-1.0, lo_open=True, hi=0.5, hi_open=True)
        )
        rho = check_real(self.rho, "rho", "kg/m³", lo=0.0, lo_open=True, hi=RHO_MAX)
        object.__setattr__(self, "rho", rho)

    @property
    def G(self) -> float:
        """Shear modulus G = E / (2 (1 + nu)), Pa."""
        return self.E / (2.0 * (1.0 + self.nu))


#: Structural steel as the study used it (E = 210 GPa, nu = 0.29, rho = 7850 kg/m³).
STEEL = Material(E=210e9, nu=0.29, rho=7850.0, name="steel")

BUILTIN_MATERIALS: dict[str, Material] = {"steel": STEEL}
