// An E_avg fit as engines print them: GGX (height-correlated Smith, Fresnel off) E_avg = 2∫ E(μ) μ dμ against
// perceptual roughness r (alpha = r^2), a degree-6 polynomial in Horner form. Generated for brdfnorm's examples
// by a least-squares fit to brdfnorm lut values on 201 nodes (coefficients rounded to 6 digits).
// Audit:
//   brdfnorm audit --formula examples/audit/e_avg_fit.glsl --function EavgApprox --args "roughness=r" \
//       --quantity E_avg --model ggx
// The same polynomial as a Python expression (examples/audit/e_avg_fit.txt):
//   brdfnorm audit --formula "$(cat examples/audit/e_avg_fit.txt)" --quantity E_avg --model ggx
float EavgApprox(float roughness)
{
    float r = roughness;
    return ((((((-1.58585 * r + 4.33191) * r - 3.01242) * r - 0.328058) * r + 0.00286358) * r
             + 0.000550941) * r + 0.999992);
}
