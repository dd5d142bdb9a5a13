"""The numbers of the materials pages (docs/materials-*.md), recomputed: Fresnel averages and the fits engines ship,
the metalness mix against the F0 blend, diffuse under a specular interface, sheen over a base.

    PYTHONPATH=src python examples/materials/questions.py        # a few minutes on one core
"""

import numpy as np

import brdfnorm as bn
from brdfnorm.materials.furnace import average_albedo
from brdfnorm.models import fresnel as fr

MU = np.array([1.0, 0.7, 0.5, 0.3, 0.1, 0.02])
THETA = np.arccos(MU)


def row(label, values):
    print(f"| {label} | " + " | ".join(f"{v:.6f}" for v in values) + " |")


def fresnel_page():
    print("## Fresnel averages\n")
    cases = [("schlick f0=0.04", fr.Fresnel("schlick", f0=0.04)),
             ("f82-tint f0=(0.944,0.776,0.373) tint=(0.9,0.8,0.7)",
              fr.Fresnel("f82-tint", f0=np.array([0.944, 0.776, 0.373]), tint=np.array([0.9, 0.8, 0.7]))),
             ("conductor gold eta=(0.143,0.374,1.442) k=(3.983,2.385,1.603)",
              fr.Fresnel("conductor", eta=np.array([0.143, 0.374, 1.442]), k=np.array([3.983, 2.385, 1.603]))),
             ("artistic r=(0.944,0.776,0.373) g=(0.9,0.8,0.7)",
              fr.Fresnel("artistic", r=np.array([0.944, 0.776, 0.373]), g=np.array([0.9, 0.8, 0.7]))),
             ("dielectric eta=1.5", fr.Fresnel("dielectric", eta=1.5)),
             ("dielectric eta=1/1.5", fr.Fresnel("dielectric", eta=1 / 1.5))]
    for label, f in cases:
        value, error = f.average()
        print(f"| {label} | {np.array2string(np.atleast_1d(value), precision=15)} | {np.max(error):.1e} |")
    for r_min in (0.0, 0.05):
        a = fr.audit_artistic_fit(201, r_min=r_min)
        print(f"\nartistic fit r in [{r_min}, 0.99]: max {a.max_error:.6f} at r={a.argmax_r:.4f} g={a.argmax_g:.4f}; "
              f"max relative {a.max_relative_error:.4f}; mean {a.mean_error:.6f}; "
              f"quadrature error {a.quadrature_error:.1e}")
    for lo, hi in ((1.0 + 1e-9, 3.0), (1 / 3.0, 1.0 - 1e-9)):
        eta = np.linspace(lo, hi, 2001)
        exact, error = fr.Fresnel("dielectric", eta=eta).average()
        diff = fr.kulla_conty_dielectric_fit(eta) - exact
        i = np.argmax(np.abs(diff))
        print(f"dielectric fit eta in [{lo:.4f}, {hi:.4f}]: max |fit - exact| {abs(diff[i]):.6f} at eta={eta[i]:.4f} "
              f"(exact {exact[i]:.6f}); quadrature error {error.max():.1e}")
    print("\nF_ms of Kulla-Conty for gold at E_avg = 0.8:",
          fr.multiple_scattering_colour(cases[2][1].average()[0], 0.8))


def metalness_page():
    print("\n## Metalness: BRDF mix vs F0 blend (white base, roughness 0.5, Schlick both), E(mu) at mu =", MU)
    for m in np.linspace(0.0, 1.0, 11):
        common = dict(base_color=(1, 1, 1), dielectric_fresnel="schlick", metal_fresnel="schlick",
                      specular_roughness=0.5, base_metalness=m)
        a = bn.albedo(bn.load("openpbr", **common), THETA).value[:, 0]
        b = bn.albedo(bn.load("openpbr", base_mix="f0-blend", **common), THETA).value[:, 0]
        row(f"M={m:.1f} mix", a)
        row(f"M={m:.1f} blend", b)
        row(f"M={m:.1f} mix-blend", a - b)
    print("\nspec defaults (exact dielectric, F82 metal, base_color 0.8) E at mu:")
    for m in (0.0, 0.5, 1.0):
        row(f"M={m}", bn.albedo(bn.load("openpbr", base_metalness=m), THETA).value[:, 0])


def diffuse_page():
    print("\n## Diffuse under a specular interface (white base, IOR 1.5), E(mu) at mu =", MU)
    for r in (0.1, 0.3, 0.6):
        for label, options in (("albedo-scaling view", {}), ("filament", {"diffuse_under": "filament"}),
                               ("symmetric", {"layering": "symmetric"}), ("reciprocal", {"layering": "reciprocal"})):
            m = bn.load("openpbr", base_color=(1, 1, 1), specular_roughness=r, **options)
            row(f"r={r} {label}", bn.albedo(m, THETA).value[:, 0])


def sheen_page():
    print("\n## Fuzz over a white Lambert base (view rule), E(mu) and the white fuzz's own E(mu) at mu =", MU)
    for lobe in ("zeltner", "charlie"):
        for r in (0.3, 0.5, 0.8):
            fuzz = bn.load(lobe, roughness=r)
            e = bn.albedo(fuzz, THETA, rtol=1e-10, method="quadrature").value[:, 0]
            avg = average_albedo(fuzz)[0][0]
            row(f"r={r} {lobe} E", e)
            print(f"r={r} {lobe} E_avg {avg:.9f}")
            common = dict(base_color=(1, 1, 1), specular_weight=0.0, fuzz_weight=1.0, fuzz_roughness=r,
                          fuzz_lobe=lobe)
            row(f"r={r} fuzz over white, view", bn.albedo(bn.load("openpbr", **common), THETA).value[:, 0])
            row(f"r={r} symmetric (E + (1-E)(1-E_avg))", e + (1 - e) * (1 - avg))
            grey = bn.load("openpbr", **common, fuzz_color=(0.5, 0.5, 0.5))
            row(f"r={r} grey fuzz 0.5 over white, view", bn.albedo(grey, THETA).value[:, 0])

if __name__ == "__main__":
    fresnel_page()
    metalness_page()
    diffuse_page()
    sheen_page()
