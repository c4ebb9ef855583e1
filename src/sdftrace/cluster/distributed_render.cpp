#include "sdftrace/cluster/distributed_render.h"

#include <algorithm>
#include <cstring>
#include <utility>

#include "sdftrace/exec/progress.h"
#include "sdftrace/render/renderer.h"

namespace sdft {

namespace {

constexpr Aov kAovs[] = {Aov::Color,     Aov::Depth,      Aov::Normal, Aov::Steps, Aov::Error,
                         Aov::TravSteps, Aov::IsectTests, Aov::Shadow, Aov::Ao,    Aov::Motion};

unsigned keptAovs(const Film& film) {
    unsigned bits = 0;
    for (Aov aov : kAovs)
        if (film.has(aov)) bits |= Film::bit(aov);
    return bits;
}

// The rows of tiles [first, last) in every channel a render fills (motion vectors come after it,
// from the frame's depth), channel by channel: f(the row's first float, its byte count). The order
// of the chunk's pixels on the wire, for both ends.
template <class FilmT, class F>
void forTileRows(FilmT& film, const FrameRenderer& frame, int first, int last, F&& f) {
    for (Aov aov : kAovs) {
        if (aov == Aov::Motion || !film.has(aov)) continue;
        const int n = aovChannels(aov);
        auto& data = film.channel(aov);
        for (int t = first; t < last; ++t) {
            const PixelRect r = frame.tile(t);
            for (int y = r.y0; y < r.y1; ++y)
                f(&data[(static_cast<size_t>(y) * film.width + r.x0) * n],
                  sizeof(float) * n * (r.x1 - r.x0));
        }
    }
}

struct Context {
    FrameView view;
    unsigned aovs = 0;
};

class TileWorker : public RoundWorker {
  public:
    TileWorker(const RenderPlan& plan, const Context& c)
        : m_film(c.view.camera.width, c.view.camera.height, c.aovs),
          m_frame(plan, c.view, m_film) {}

    void run(int first, int last, ByteWriter& out) override {
        m_frame.renderTiles(first, last);
        forTileRows(std::as_const(m_film), m_frame, first, last,
                    [&](const float* row, size_t bytes) { out.append(row, bytes); });
    }
    Bytes finish() override {
        ByteWriter w;
        w.put(m_frame.stats());
        return std::move(w.bytes());
    }

  private:
    Film m_film;
    FrameRenderer m_frame;
};

}  // namespace

RenderStats renderAcross(WorkFarm& farm, const RenderPlan& plan, const FrameView& view, Film& film,
                         bool progress, Bytes prefix) {
    FrameRenderer frame(plan, view, film);  // rank 0's share renders on the farm's thread
    Context c{view, keptAovs(film)};
    c.aovs &= ~Film::bit(Aov::Motion);
    ByteWriter context;
    context.append(prefix.data(), prefix.size());
    context.put(c);
    RenderStats others;
    int otherThreads = 0;
    Progress bar(plan.settings.pathTracing ? "path tracing" : "render",
                 static_cast<uint64_t>(frame.tileCount()), progress);
    RoundPlan round;
    round.context = std::move(context.bytes());
    round.items = frame.tileCount();
    round.local = [&](int first, int last) { frame.renderTiles(first, last); };
    round.onResult = [&](int, int first, int last, ByteReader& in) {
        forTileRows(film, frame, first, last,
                    [&](float* row, size_t bytes) { in.read(row, bytes); });
    };
    round.onFinish = [&](int, const Bytes& b) {
        ByteReader in(b);
        const auto s = in.get<RenderStats>();
        others.add(s);
        otherThreads += s.threads;
    };
    round.progress = &bar;
    farm.round(round);
    RenderStats total = frame.stats();
    total.add(others);
    total.threads += otherThreads;
    total.ranks = farm.ranks();
    return total;
}

std::unique_ptr<RoundWorker> tileWorker(const RenderPlan& plan, ByteReader& context) {
    return std::make_unique<TileWorker>(plan, context.get<Context>());
}

void packFilm(const Film& film, ByteWriter& out) {
    out.put(film.width);
    out.put(film.height);
    out.put(keptAovs(film));
    for (Aov aov : kAovs)
        if (film.has(aov)) {
            const std::vector<float>& d = film.channel(aov);
            out.append(d.data(), d.size() * sizeof(float));
        }
}

Film unpackFilm(ByteReader& in) {
    const int w = in.get<int>(), h = in.get<int>();
    const auto aovs = in.get<unsigned>();
    Film film(w, h, aovs);
    for (Aov aov : kAovs)
        if (film.has(aov)) {
            std::vector<float>& d = film.channel(aov);
            in.read(d.data(), d.size() * sizeof(float));
        }
    return film;
}

}  // namespace sdft
