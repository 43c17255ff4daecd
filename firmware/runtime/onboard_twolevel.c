/*
 * onboard_twolevel.c -- the two-level part of the on-board plant (see
 * onboard.h): the controller's udc_v and prev_sw, the switching state
 * sw = Sa*4 + Sb*2 + Sc as the amplitude-invariant space vector
 *   u_alpha = (2/3)*Udc*(Sa - (Sb + Sc)/2),  u_beta = (Udc/sqrt(3))*(Sb - Sc)
 * (twolevel_plant.c) held over the whole period, and the timing rule of
 * twolevel_sim.c: with delay compensation the decision of k acts in k+1.
 */
#include "onboard.h"
#include "onboard_config.h"

#define ONB_SQRT3_INV 0.57735027f

static uint16_t prev_sw;

void onb_topo_reset(void)
{
    prev_sw = 0u;
}

void onb_topo_input(const onb_plant_t *p, mpc_input_t *in)
{
    (void)p;
    in->udc_v = MPC_ENCODE_udc_v(ONB_UDC);
    in->prev_sw = prev_sw;
}

uint16_t onb_topo_decision(const mpc_output_t *out)
{
    return out->sw;
}

int16_t onb_topo_apply(onb_plant_t *p, const mpc_output_t *out, float load_nm)
{
    onb_segment_t seg;
    const uint16_t dec = out->sw;
    uint16_t sw;
    float sa, sb, sc;
    if (dec > 7u) {
        return -3;
    }
    sw = (ONB_DELAY_COMPENSATION != 0) ? prev_sw : dec;
    sa = (float)((sw >> 2) & 1u);
    sb = (float)((sw >> 1) & 1u);
    sc = (float)(sw & 1u);
    seg.ua0 = (2.0f / 3.0f) * ONB_UDC * (sa - 0.5f * (sb + sc));
    seg.ub0 = ONB_UDC * ONB_SQRT3_INV * (sb - sc);
    seg.ua1 = 0.0f;
    seg.ub1 = 0.0f;
    seg.ka = 0.0f;
    seg.kb = 0.0f;
    seg.zero = (uint16_t)(sw == 0u || sw == 7u);
    onb_advance(p, &seg, load_nm, ONB_DT, ONB_SUBSTEPS);
    prev_sw = dec;
    return 0;
}
