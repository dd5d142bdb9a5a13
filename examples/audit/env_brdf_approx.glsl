// A split-sum "EnvBRDFApprox"-style analytic fit (Karis 2014, "Physically Based Shading on Mobile"; the form
// engines print it in). Returns (scale, bias) of the split-sum DFG for roughness (r, alpha = r^2) and NoV.
// Written here from the published constants; audit it with
//   brdfnorm audit --formula examples/audit/env_brdf_approx.glsl --function EnvBRDFApprox \
//       --args "Roughness=r,NoV=mu" --quantity DFG_f0,DFG_f90 --model ggx
vec2 EnvBRDFApprox(float Roughness, float NoV)
{
    const vec4 c0 = vec4(-1.0, -0.0275, -0.572, 0.022);
    const vec4 c1 = vec4(1.0, 0.0425, 1.04, -0.04);
    vec4 r = Roughness * c0 + c1;
    float a004 = min(r.x * r.x, exp2(-9.28 * NoV)) * r.x + r.y;
    return vec2(-1.04, 1.04) * a004 + r.zw;
}
