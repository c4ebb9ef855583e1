#include "sdftrace/render/primary_pixel.h"

#include "sdftrace/render/render_plan.h"

namespace sdft {

bool usesMinMax(const RenderPlan& plan) {
    return plan.ddaGrid && plan.settings.minMaxResolution > 0;
}

MinMaxBuffer primaryMinMax(const RenderPlan& plan, const Camera& camera) {
    if (!usesMinMax(plan)) return {};
    return MinMaxBuffer::build(plan.ddaGrid->view(), camera, plan.settings.minMaxResolution);
}

namespace {

// The index in the tape's grids of the plan's DDA grid: the tape of a lone grid has one grid leaf.
int ddaGridIndex(const RenderPlan& plan) {
    if (!plan.ddaGrid) return -1;
    const TapeView t = plan.tape.view();
    for (uint32_t i = 0; i < t.count; ++i) {
        if (t.instrs[i].op != Op::Grid) continue;
        const int g = static_cast<int>(t.consts[t.instrs[i].k]);
        SDFT_CHECK(t.grids[g].samples == plan.ddaGrid->view().samples &&
                   t.grids[g].blockSamples == plan.ddaGrid->view().blockSamples);
        return g;
    }
    SDFT_CHECK(!"a DDA grid without a grid leaf in the tape");
    return -1;
}

}  // namespace

PrimaryPixelView primaryPixelView(const RenderPlan& plan, const FrameView& frame,
                                  MeshPrimaryView meshes) {
    SDFT_CHECK(!plan.meshPrimary || meshes.count > 0);  // the triangles must come with the plan
    PrimaryPixelView v;
    v.field = plan.tape.view();
    v.primaryField = plan.primaryField ? plan.primaryField->view() : v.field;
    v.meshesOnly = plan.meshPrimary && !plan.primaryField;
    if (plan.meshPrimary) v.meshes = meshes;
    v.camera = Camera(frame.camera);
    v.options = plan.settings.trace;
    v.options.pixelRadius = v.camera.pixelRadius();
    v.maxDistance = plan.settings.maxDistance;
    v.horizon = plan.horizon;
    v.normalSpacingMin = plan.settings.normalSpacingMin;
    v.jitter[0] = frame.pixelJitter[0];
    v.jitter[1] = frame.pixelJitter[1];
    v.normals = plan.settings.normals;
    v.ddaGrid = ddaGridIndex(plan);
    v.gridTrace = plan.settings.gridTrace;
    v.gridNormals = plan.settings.gridNormals;
    if (plan.ddaGrid) v.gridStartSign = gridSignAt(plan.ddaGrid->view(), frame.camera.eye);
    return v;
}

}  // namespace sdft
