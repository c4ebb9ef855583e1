// Scenes over time (issue 16): keyframed values anywhere a scene takes numbers, the scene of an
// instant, assets shared across instants, and one clear error for bad keyframes.
#include "sdftrace/scene/animated_scene.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "sdftrace/core/error.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/scene/parse_scene.h"

namespace sdft {
namespace {

const std::string kMeshes = std::string(SDFT_SOURCE_DIR) + "/data/meshes/";

// The message of the InputError f throws, "" when it throws none.
std::string inputErrorOf(const std::function<void()>& f) {
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

float fieldAt(const Scene& s, Vec3 p) {
    return compileTape(s.root, {.boundsCulling = false}).eval(p);
}

// A ball moving from x = 0 to x = 2 over two seconds, growing, seen by a camera that rises, lit
// by a light that swings on a smooth looping path; the ball's rotation angle is keyed by itself.
const char* kMoving = R"({
  "camera": {"eye": {"keyframes": [{"time": 0, "value": [0, 1, 6]}, {"time": 2, "value": [0, 3, 6]}]},
             "target": [1, 0, 0]},
  "lights": [{"type": "point", "intensity": 10,
              "position": {"keyframes": [{"time": 0, "value": [4, 4, 0]}, {"time": 1, "value": [0, 4, 4]},
                                         {"time": 2, "value": [-4, 4, 0]}, {"time": 3, "value": [4, 4, 0]}],
                           "interpolation": "smooth", "extrapolation": "loop"}}],
  "objects": [{"type": "sphere",
               "radius": {"keyframes": [{"time": 0, "value": 0.5}, {"time": 2, "value": 1}]},
               "rotate": {"axis": [0, 1, 0], "angle": {"keyframes": [{"time": 0, "value": 0},
                                                                    {"time": 2, "value": 90}]}},
               "translate": {"keyframes": [{"time": 0, "value": [0, 0, 0]}, {"time": 2, "value": [2, 0, 0]}]}}]
})";

TEST(AnimatedScene, TheSceneOfAnInstantHasItsKeyframedValues) {
    const AnimatedScene anim = AnimatedScene::fromText(kMoving, "moving.json");
    EXPECT_TRUE(anim.time().animated);
    EXPECT_EQ(anim.time().start, 0);
    EXPECT_EQ(anim.time().end, 3);  // the keys' span: the light's last key
    for (double t : {0.0, 0.5, 1.0, 2.0, 2.5}) {
        const Scene s = anim.describeAt(t);
        const double u = std::min(t, 2.0) / 2;  // clamped after the last key
        const Vec3 centre(static_cast<float>(2 * u), 0, 0);
        const float radius = static_cast<float>(0.5 + 0.5 * u);
        EXPECT_NEAR(fieldAt(s, centre), -radius, 1e-5f) << t;
        EXPECT_NEAR(fieldAt(s, centre + Vec3(0, radius, 0)), 0, 1e-5f) << t;
        EXPECT_NEAR(s.camera.eye.y, 1 + 2 * u, 1e-6) << t;
        ASSERT_EQ(s.lighting.lights.size(), 1u);
    }
    // The light loops every 3 s and passes its keys exactly.
    EXPECT_NEAR(anim.describeAt(1).lighting.lights[0].position.z, 4, 1e-6);
    const Vec3 a = anim.describeAt(0.4).lighting.lights[0].position,
               b = anim.describeAt(3.4).lighting.lights[0].position;
    EXPECT_NEAR(length(a - b), 0, 1e-5);
    // A static description of an animated file is its start.
    const Scene start = describeSceneText(kMoving, "moving.json");
    EXPECT_NEAR(fieldAt(start, Vec3(0)), -0.5f, 1e-5f);
    EXPECT_TRUE(start.time.animated);
}

TEST(AnimatedScene, TheAnimationBlockSetsTheSpanAndRate) {
    const std::string text = R"({"animation": {"start": 0.5, "end": 4, "fps": 24},
        "objects": [{"type": "sphere", "radius": 1}]})";
    const AnimatedScene anim = AnimatedScene::fromText(text, "a.json");
    EXPECT_FALSE(anim.time().animated);
    EXPECT_EQ(anim.time().start, 0.5);
    EXPECT_EQ(anim.time().end, 4);
    EXPECT_EQ(anim.time().fps, 24);
}

// A rigid mesh whose transform is keyframed is baked once for every instant; a keyframed bake
// parameter bakes again where its value changes.
TEST(AnimatedScene, InstantsShareTheirAssets) {
    const std::string text = R"({"objects": [
        {"mesh": ")" + kMeshes +
                             R"(teapot.obj", "resolution": 16,
         "translate": {"keyframes": [{"time": 0, "value": [0, 0, 0]}, {"time": 1, "value": [3, 0, 0]}]}},
        {"mesh": ")" + kMeshes +
                             R"(teapot.obj", "translate": [0, 5, 0],
         "resolution": {"keyframes": [{"time": 0, "value": 12}, {"time": 1, "value": 20}],
                        "interpolation": "step"}}]})";
    const AnimatedScene anim = AnimatedScene::fromText(text, "m.json");
    AssetCache cache;
    size_t baked = 0, cached = 0;
    for (double t : {0.0, 0.25, 0.5, 0.75, 1.0}) {
        Scene s = anim.describeAt(t);
        const PrepareStats st = prepareScene(s, cache);
        baked += st.baked;
        cached += st.cached;
    }
    EXPECT_EQ(baked, 3u);  // the rigid teapot once, the other at resolution 12, then at 20
    EXPECT_EQ(cached, 7u);
}

// A closed cube of side 1 centred at (x, 0, 0), as OBJ text.
std::string cubeObj(float x) {
    std::string s;
    for (int v = 0; v < 8; ++v)
        s += "v " + std::to_string(x + ((v & 1) ? 0.5f : -0.5f)) + " " +
             std::to_string((v & 2) ? 0.5f : -0.5f) + " " + std::to_string((v & 4) ? 0.5f : -0.5f) +
             "\n";
    // Two triangles per face, wound outwards (vertex v at bits x = 1, y = 2, z = 4; OBJ is
    // 1-based).
    for (const char* f : {"1 3 4 2", "5 6 8 7", "1 2 6 5", "3 7 8 4", "1 5 7 3", "2 4 8 6"}) {
        int a, b, c, d;
        std::sscanf(f, "%d %d %d %d", &a, &b, &c, &d);
        s += "f " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(c) + "\n";
        s += "f " + std::to_string(a) + " " + std::to_string(c) + " " + std::to_string(d) + "\n";
    }
    return s;
}

// A mesh sequence plays one file per frame, its frame number keyframed; past frames leave the
// cache, and a missing frame is an error of that instant naming the file.
TEST(AnimatedScene, AMeshSequencePlaysOneFilePerFrame) {
    namespace fs = std::filesystem;
    const fs::path dir =
        fs::temp_directory_path() / ("sdft_sequence_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    for (int k = 0; k < 2; ++k)  // frames 0 and 1; frame 2 is missing
        std::ofstream(dir / ("cube_" + std::to_string(k) + ".obj")) << cubeObj(3.0f * k);
    const std::string text = R"({"objects": [{"mesh": "cube_%d.obj", "resolution": 16,
        "frame": {"keyframes": [{"time": 0, "value": 0}, {"time": 3, "value": 3}]}}]})";
    const AnimatedScene anim = AnimatedScene::fromText(text, "seq.json", dir.string());
    AssetCache cache;
    AnimatedScene::InstantAssets used;
    const Scene first = anim.at(0.5, cache, {}, &used);  // frame 0
    EXPECT_LT(fieldAt(first, Vec3(0, 0, 0)), -0.2f);     // 0.5 over the grid's Lipschitz bound
    EXPECT_GT(fieldAt(first, Vec3(3, 0, 0)), 0.2f);
    cache.keepOnly(used.keys);
    const Scene second = anim.at(1.5, cache, {}, &used);  // frame 1
    EXPECT_EQ(used.stats.baked, 1u);
    cache.keepOnly(used.keys);
    EXPECT_EQ(cache.size(), 1u);  // frame 0's grid is gone
    EXPECT_LT(fieldAt(second, Vec3(3, 0, 0)), -0.2f);
    EXPECT_GT(fieldAt(second, Vec3(0, 0, 0)), 0.2f);
    const std::string msg = inputErrorOf([&] { anim.at(2.5, cache); });
    EXPECT_FALSE(msg.empty()) << "a missing frame was accepted";
    EXPECT_NE(msg.find("cube_2.obj"), std::string::npos) << msg;
    EXPECT_NE(msg.find("(at time 2.5 s)"), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    fs::remove_all(dir);
}

// A deforming mesh regenerated every frame by RTSDF's pipeline (dynamic "rtsdf"): one grid for
// all frames, accumulated with decay; it follows the mesh when it changes. "rebake" bakes every
// frame afresh.
TEST(AnimatedScene, DynamicMeshesAreRegeneratedEveryFrame) {
    namespace fs = std::filesystem;
    const fs::path dir = fs::temp_directory_path() / ("sdft_dynamic_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    std::ofstream(dir / "cube_0.obj") << cubeObj(0);
    std::ofstream(dir / "cube_1.obj") << cubeObj(0.3f);
    // Frame 0 until t = 1, frame 1 after.
    const std::string frame = R"("frame": {"keyframes": [{"time": 0, "value": 0}, {"time": 1,
        "value": 1}], "interpolation": "step"})";
    const AnimatedScene rtsdf = AnimatedScene::fromText(
        R"({"objects": [{"mesh": "cube_%d.obj", "resolution": 32, )" + frame +
            R"(, "dynamic": {"method": "rtsdf", "rays": 4, "alpha": 0.8}}]})",
        "dyn.json", dir.string());
    AssetCache cache;
    AnimatedScene::InstantAssets used;
    const Vec3 p(0.7f, 0, 0);  // 0.2 outside the first cube, 0.1 inside the second
    float before = 0, after = 0;
    std::shared_ptr<const Grid> first;
    for (int i = 0; i < 40; ++i) {
        const double t = i < 10 ? 0.05 * i : 1.0 + 0.05 * i;
        const Scene s = rtsdf.at(t, cache, {}, &used);
        EXPECT_EQ(used.stats.baked, 1u) << i;  // every frame regenerated, none cached
        (i < 10 ? before : after) = fieldAt(s, p);
        // Each frame's grid is a complete block grid of its own, the first frame's layout
        // refreshed.
        const std::shared_ptr<const Grid> g = cache.rtsdfHistory("dyn.json: /objects/0/mesh").grid;
        ASSERT_TRUE(g && g->isComplete()) << i;
        if (!first) first = g;
        EXPECT_EQ(g->blockNeighbors(), first->blockNeighbors()) << i;
        EXPECT_EQ(g->blockSamples().size(), first->blockSamples().size()) << i;
        if (i > 0) {
            EXPECT_NE(g, first) << i;
        }
    }
    EXPECT_EQ(cache.rtsdfHistory("dyn.json: /objects/0/mesh").frames, 40);
    EXPECT_GT(before, 0.05f);
    EXPECT_LT(after, -0.02f);
    const AnimatedScene rebake =
        AnimatedScene::fromText(R"({"objects": [{"mesh": "cube_%d.obj", "resolution": 16, )" +
                                    frame + R"(, "dynamic": {"method": "rebake"}}]})",
                                "re.json", dir.string());
    for (double t : {0.0, 0.5, 1.5}) {
        const Scene s = rebake.at(t, cache, {}, &used);
        EXPECT_EQ(used.stats.baked, 1u);
        EXPECT_EQ(fieldAt(s, p) < 0, t > 1);
    }
    fs::remove_all(dir);
}

// RTSDF's grid covers its volume like its 3D textures: beyond the ray mask it holds the coarse
// SDF's distances (over the grid's Lipschitz bound), not a narrow band's block-gap lower bounds,
// which SDF soft shadows read as near misses. A played mesh's grid holds its whole clip: the
// tube bent over at the clip's end lies beyond the bounds of its upright first frame.
TEST(AnimatedScene, RtsdfGridsHoldDistancesEverywhereAndTheWholeClip) {
    const AnimatedScene anim = AnimatedScene::fromText(
        R"({"objects": [{"mesh": "bending_tube.gltf", "resolution": 48,
            "play": {"loop": false}, "dynamic": {"method": "rtsdf", "rays": 4}}]})",
        "tube.json", kMeshes + "animated");
    AssetCache cache;
    const Scene first = anim.at(0, cache);
    const Tape tape = compileTape(first.root, {.boundsCulling = false});
    const Bounds3 box = tape.bounds();
    const float coarse = 2 * maxComponent(box.extent()) / 48;
    // Upright at t = 0: a tube of radius 0.25 along y from 0 to 2.
    auto exact = [](Vec3 p) {
        const float radial = std::sqrt(p.x * p.x + p.z * p.z) - 0.25f;
        const float axial = std::max(-p.y, p.y - 2.0f);
        return std::min(std::max(radial, axial), 0.0f) +
               length(Vec3(std::max(radial, 0.0f), std::max(axial, 0.0f), 0));
    };
    int far = 0;
    float worstRatio = INFINITY;
    for (int i = 0; i < 200; ++i) {
        const Vec3 p = box.lo + box.extent() * Vec3(0.05f + 0.9f * ((i * 37) % 100) / 100.0f,
                                                    0.05f + 0.9f * ((i * 53) % 100) / 100.0f,
                                                    0.05f + 0.9f * ((i * 71) % 100) / 100.0f);
        if (exact(p) < 3 * coarse) continue;
        ++far;
        const float f = fieldAt(first, p);
        worstRatio = std::min(worstRatio, f / exact(p));
        EXPECT_LE(f, exact(p) + 2 * coarse);
    }
    EXPECT_GT(far, 40);
    // Measured: 0.49 (the grid's Lipschitz bound, about 2 from the rays' noisy distances, divides
    // it); the narrow band's block-gap bound gave 0.048 here.
    EXPECT_GT(worstRatio, 0.4f);
    for (int k = 1; k <= 12; ++k) anim.at(2.0 * k / 12, cache);
    const Scene bent = anim.at(2, cache);
    EXPECT_LT(fieldAt(bent, Vec3(0.5f, 1.0f, 0)), 0) << "the bent half, beyond the first bounds";
}

// Bad keyframes, and values that are out of range at a key, are one-line errors at load time
// naming the JSON path (and the time, for a value that is bad only at some instant).
TEST(AnimatedScene, BadKeyframesAreOneClearError) {
    auto sphere = [](const std::string& radius) {
        return R"({"objects": [{"type": "sphere", "radius": )" + radius + "}]}";
    };
    const struct {
        std::string text, expected;
    } cases[] = {
        {sphere(R"({"keyframes": [{"time": 1, "value": 1}, {"time": 0, "value": 2}]})"),
         "/objects/0/radius/keyframes/1/time: time 0 is not after the previous key's 1"},
        {sphere(R"({"keyframes": [{"time": 1, "value": 1}, {"time": 1, "value": 2}]})"),
         "/objects/0/radius/keyframes/1/time: time 1 is not after the previous key's 1"},
        {sphere(R"({"keyframes": []})"), "/objects/0/radius/keyframes: expected at least one"},
        {sphere(R"({"keyframes": [{"time": 0, "value": 1}, {"time": 1, "value": [1, 2]}]})"),
         "/objects/0/radius/keyframes/1/value: expected a value of the same shape"},
        {sphere(R"({"keyframes": [{"time": 0, "value": "big"}]})"),
         "/objects/0/radius/keyframes/0/value: expected a number or an array"},
        {sphere(R"({"keyframes": [{"time": 0, "value": {"keyframes": []}}]})"),
         "/objects/0/radius/keyframes/0/value: expected a number or an array"},
        {sphere(R"({"keyframes": [{"time": 0}]})"),
         "/objects/0/radius/keyframes/0: missing required key 'value'"},
        {sphere(R"({"keyframes": [{"time": 0, "value": 1, "ease": 2}]})"),
         "/objects/0/radius/keyframes/0/ease: unknown key; accepted here: time, value"},
        {sphere(R"({"keyframes": [{"time": 0, "value": 1}], "interpolation": "cubic"})"),
         "/objects/0/radius/interpolation: unknown interpolation 'cubic'; accepted: linear, "
         "smooth, step"},
        {sphere(R"({"keyframes": [{"time": 0, "value": 1}], "extrapolation": "mirror"})"),
         "/objects/0/radius/extrapolation: unknown extrapolation 'mirror'; accepted: clamp, loop"},
        {sphere(R"({"keyframes": 3})"), "/objects/0/radius/keyframes: expected a list"},
        {sphere(R"({"keyframes": [{"time": 0, "value": 1}, {"time": 2, "value": -1}]})"),
         "/objects/0/radius: expected a positive radius, got -1 (at time 2 s)"},
        {R"({"animation": {"start": 2, "end": 1}, "objects": [{"type": "sphere", "radius": 1}]})",
         "/animation/end: the end time 1 is before the start time 2"},
        {R"({"animation": {"fps": 0}, "objects": [{"type": "sphere", "radius": 1}]})",
         "/animation/fps: expected frames per second in (0, 1000]"},
        {R"({"objects": [{"mesh": "frames/m_%04d.obj"}]})",
         "/objects/0/mesh: 'frames/m_%04d.obj' is a file pattern; give \"frame\""},
        {R"({"objects": [{"mesh": "m_%d_%d.obj", "frame": 2}]})",
         "/objects/0/mesh: 'm_%d_%d.obj': a mesh sequence's file pattern holds one frame-number"},
        {R"({"objects": [{"mesh": "m_%s.obj", "frame": 2}]})",
         "/objects/0/mesh: 'm_%s.obj': a mesh sequence's file pattern holds one"},
        {R"({"objects": [{"mesh": "m_%d.obj", "frame": -1}]})",
         "/objects/0/frame: expected a frame number >= 0 (floored), got -1"},
        {R"({"objects": [{"mesh": "m.obj", "dynamic": {"method": "fast"}}]})",
         "/objects/0/dynamic/method: unknown dynamic method 'fast'; accepted: rtsdf, rebake"},
        {R"({"objects": [{"mesh": "m.obj", "dynamic": {"method": "rtsdf", "alpha": 1}}]})",
         "/objects/0/dynamic/alpha: expected a decay factor in [0, 1), got 1"},
        {R"({"objects": [{"mesh": "m.obj", "dynamic": {"method": "rtsdf", "rays": 0}}]})",
         "/objects/0/dynamic/rays: expected an integer in [1, 4096], got 0"},
        {R"({"objects": [{"mesh": "m.obj", "dynamic": {"method": "rebake", "rays": 4}}]})",
         "/objects/0/dynamic/rays: applies to \"method\": \"rtsdf\" only"},
        {R"({"objects": [{"mesh": "m.obj", "method": "jfa", "dynamic": {"method": "rtsdf"}}]})",
         "/objects/0/method: a mesh with \"dynamic\""},
    };
    for (const auto& c : cases) {
        const std::string msg = inputErrorOf([&] { AnimatedScene::fromText(c.text, "bad.json"); });
        EXPECT_FALSE(msg.empty()) << "accepted: " << c.text;
        EXPECT_EQ(msg.rfind("bad.json: ", 0), 0u) << msg;
        EXPECT_NE(msg.find(c.expected), std::string::npos) << msg << "\nexpected: " << c.expected;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
        // The static description reports the same problems (at its start time).
        EXPECT_THROW(describeSceneText(c.text, "bad.json"), InputError) << c.text;
    }
}

// A scene with thousands of keys loads quickly (it is checked at 256 key times and its ends); a
// value bad at the last key is still caught at load.
TEST(AnimatedScene, ManyKeysAreCheckedAtASample) {
    std::string keys;
    for (int k = 0; k < 3000; ++k)
        keys += (k ? ", " : "") + std::string("{\"time\": ") + std::to_string(k) +
                ", \"value\": " + (k == 2999 ? "-1" : "1") + "}";
    const std::string text =
        R"({"objects": [{"type": "sphere", "radius": {"keyframes": [)" + keys + "]}}]}";
    const std::string msg = inputErrorOf([&] { AnimatedScene::fromText(text, "many.json"); });
    EXPECT_FALSE(msg.empty()) << "a negative radius at the last key was accepted";
    EXPECT_NE(msg.find("(at time 2999 s)"), std::string::npos) << msg;
}

// A value that is only bad between keys is an error of that instant, naming the time.
TEST(AnimatedScene, AValueBadOnlyBetweenKeysNamesItsTime) {
    const std::string text = R"({"camera": {"width": {"keyframes": [{"time": 0, "value": 100},
        {"time": 1, "value": 201}]}}, "objects": [{"type": "sphere", "radius": 1}]})";
    const AnimatedScene anim = AnimatedScene::fromText(text, "w.json");
    EXPECT_EQ(anim.describeAt(0).camera.width, 100);
    EXPECT_EQ(anim.describeAt(1).camera.width, 201);
    const std::string msg = inputErrorOf([&] { anim.describeAt(0.5); });
    EXPECT_FALSE(msg.empty()) << "a width of 150.5 accepted";
    EXPECT_NE(msg.find("w.json: /camera/width: expected an integer"), std::string::npos) << msg;
    EXPECT_NE(msg.find("(at time 0.5 s)"), std::string::npos) << msg;
}

// A skinned mesh plays its own animation (the tube of scripts/make-bending-tube.py: its upper
// half bends 90 degrees towards -x while its root slides 1 unit along +x over 2 s): the scene at
// t holds the pose at start + speed * t, looped into the clip.
TEST(AnimatedScene, AMeshPlaysItsOwnAnimation) {
    auto scene = [](const std::string& play) {
        return AnimatedScene::fromText(
            R"({"animation": {"end": 4}, "objects": [{"mesh": "bending_tube.gltf",
                "resolution": 48, "band": 4, "play": )" +
                play + "}]}",
            "tube.json", kMeshes + "animated");
    };
    const AnimatedScene plain = scene("{}");
    AssetCache cache;
    const AnimatedScene once = scene(R"({"loop": false})");
    AssetCache held;
    const Scene start = plain.at(0, cache), end = once.at(2, held);
    const Vec3 tip(0, 1.9f, 0), bent(0.5f, 1.0f, 0);
    EXPECT_LT(fieldAt(start, tip), 0) << "upright at t = 0";
    EXPECT_GT(fieldAt(start, bent), 0);
    EXPECT_GT(fieldAt(end, tip), 0) << "bent over at t = 2";
    EXPECT_LT(fieldAt(end, bent), 0);
    // Looped: t = 3 is the clip's second 1; twice the speed reaches it at t = 0.5.
    const Scene looped = plain.at(3, cache), one = plain.at(1, cache);
    AssetCache other;
    const Scene fast = scene(R"({"speed": 2, "animation": "bend"})").at(0.5, other);
    for (const Vec3 p : {tip, bent, Vec3(0.3f, 1.6f, 0.1f), Vec3(0.1f, 0.4f, 0)}) {
        EXPECT_EQ(fieldAt(looped, p), fieldAt(one, p));
        EXPECT_EQ(fieldAt(fast, p), fieldAt(one, p));
    }
    // Not looped: held at the clip's end; looped, its end is its start.
    EXPECT_EQ(fieldAt(once.at(3, held), bent), fieldAt(end, bent));
    EXPECT_EQ(fieldAt(plain.at(2, cache), bent), fieldAt(start, bent));
}

TEST(AnimatedScene, PlayingWhatCannotPlayIsOneClearError) {
    auto errorOf = [](const std::string& object) {
        return inputErrorOf([&] {
            AssetCache cache;
            AnimatedScene::fromText(R"({"objects": [)" + object + "]}", "play.json", kMeshes)
                .at(0, cache);
        });
    };
    EXPECT_NE(errorOf(R"({"mesh": "bunny_npm.obj", "play": {}})")
                  .find("/objects/0/mesh: unsupported mesh file 'bunny_npm.obj' to play"),
              std::string::npos);
    // The tube without its animation: a glTF that has none.
    const std::string still = (std::filesystem::temp_directory_path() /
                               ("sdft_still_" + std::to_string(getpid()) + ".gltf"))
                                  .string();
    {
        std::ifstream in(kMeshes + "animated/bending_tube.gltf");
        nlohmann::json tube = nlohmann::json::parse(in);
        tube.erase("animations");
        std::ofstream(still) << tube.dump();
    }
    const std::string noAnimation = errorOf(R"({"mesh": ")" + still + R"(", "play": {}})");
    std::filesystem::remove(still);
    EXPECT_NE(noAnimation.find("play.json: /objects/0/play: " + still +
                               " has no skeletal or morph animation"),
              std::string::npos)
        << noAnimation;
    const struct {
        std::string play, expected;
    } cases[] = {
        {R"({"animation": "walk"})",
         "play.json: /objects/0/play/animation: no animation named 'walk' in "},
        {R"({"animation": 2})", "/objects/0/play/animation: animation 2 of "},
        {R"({"animation": 2})", "which has 1: 0 'bend'"},
        {R"({"speed": "fast"})", "/objects/0/play/speed"},
        {R"({"rate": 2})", "/objects/0/play/rate"},
    };
    for (const auto& c : cases) {
        const std::string e =
            errorOf(R"({"mesh": "animated/bending_tube.gltf", "play": )" + c.play + "}");
        EXPECT_NE(e.find(c.expected), std::string::npos) << c.play << ": " << e;
    }
}

}  // namespace
}  // namespace sdft
