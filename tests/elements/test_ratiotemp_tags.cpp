// ratiotemp's stream tags: what a recording says about itself (units, model and its
// fingerprint, profile, method, e-slope, exposure), pushed before the first frame, again when
// they change, and merged with upstream's stream tags rather than replaced by them.
#include <string>
#include <vector>

#include "element_support.h"
#include "pyrocam/runtime/model.h"

namespace pyrocam::test {
namespace {

std::string rgb_model_path() {
  const char* dir = g_getenv("PYROCAM_TEST_MODEL_DIR");
  return std::string(dir ? dir : ".") + "/test-model-rgb.json";
}

// One frame of three 4x2 band planes of a plausible graybody (values do not matter here).
GstBuffer* frame() {
  std::vector<float> planes;
  for (float v : {120.f, 100.f, 60.f}) planes.insert(planes.end(), 8, v);
  return buffer_from(planes);
}
const char* kCaps =
    "video/x-pyrocam-bands,format=F32LE,bands=3,layout=bayer,width=4,height=2,framerate=30/1";

class RatioTempTags : public HarnessTest {
 protected:
  RatioTempTags() : HarnessTest("ratiotemp") {}
  // Pushes a frame and returns the stream tag lists that came out before it (caller unrefs).
  std::vector<GstTagList*> push_frame() {
    GstBuffer* out = push_pull_buffer(h, frame());
    EXPECT_NE(out, nullptr);
    if (out) gst_buffer_unref(out);
    std::vector<GstTagList*> tags;
    while (GstEvent* e = gst_harness_try_pull_event(h)) {
      if (GST_EVENT_TYPE(e) == GST_EVENT_TAG) {
        GstTagList* t = nullptr;
        gst_event_parse_tag(e, &t);
        EXPECT_EQ(gst_tag_list_get_scope(t), GST_TAG_SCOPE_STREAM);
        tags.push_back(gst_tag_list_ref(t));
      }
      gst_event_unref(e);
    }
    return tags;
  }
  static std::string text(const GstTagList* t, const char* tag) {
    gchar* v = nullptr;
    if (!gst_tag_list_get_string(t, tag, &v)) return "";
    std::string s = v;
    g_free(v);
    return s;
  }
  static void unref_all(std::vector<GstTagList*>& v) {
    for (GstTagList* t : v) gst_tag_list_unref(t);
    v.clear();
  }
};

TEST_F(RatioTempTags, describe_the_recording_and_follow_changes) {
  const ThermalModel model = load_model(rgb_model_path());
  ASSERT_EQ(model.fingerprint.size(), 16u);
  start("ratiotemp method=likelihood model=" + rgb_model_path(), kCaps);
  // Upstream's stream tags (a camera's exposure, 1/500 s, and a name) come before the frame.
  // The exposure tag is libgsttag's (GST_TAG_CAPTURING_SHUTTER_SPEED), registered here as it is.
  if (!gst_tag_exists("capturing-shutter-speed"))
    gst_tag_register("capturing-shutter-speed", GST_TAG_FLAG_META, GST_TYPE_FRACTION,
                     "capturing shutter speed", "Shutter speed used when capturing an image, in s",
                     nullptr);
  GstTagList* upstream = gst_tag_list_new("capturing-shutter-speed", 1, 500, GST_TAG_ARTIST,
                                          "camera 7", GST_TAG_COMMENT, "upstream's", nullptr);
  gst_tag_list_set_scope(upstream, GST_TAG_SCOPE_STREAM);
  ASSERT_TRUE(gst_harness_push_event(h, gst_event_new_tag(upstream)));

  auto tags = push_frame();
  ASSERT_EQ(tags.size(), 1u) << "upstream's tags must come out merged, in one event";
  const std::string comment = text(tags[0], GST_TAG_COMMENT);
  EXPECT_EQ(comment,
            "pyrocam-recording; quantity=temperature; unit=0.1 K; no-reading=0; "
            "model=test-model-rgb.json; model-fingerprint=" +
                model.fingerprint + "; profile=" + model.profile().name +
                "; method=likelihood; e-slope=0 %/100 nm; partial-bands=safe; "
                "misfit-probability=0; blur-correction=off; brightness-radius=0; "
                "exposure=2000 us");
  EXPECT_NE(text(tags[0], GST_TAG_TITLE).find("0.1 K per code"), std::string::npos);
  EXPECT_EQ(text(tags[0], GST_TAG_ARTIST), "camera 7");  // upstream's other tags stay
  unref_all(tags);

  // Nothing changed: no new tags. A new method and e-slope: new tags before the next frame.
  EXPECT_TRUE(push_frame().empty());
  GstElement* ratiotemp = find_element(h, "ratiotemp");
  g_object_set(ratiotemp, "e-slope", -12.5, "brightness-radius", 2u, "misfit-probability", 1e-6,
               nullptr);
  gst_util_set_object_arg(G_OBJECT(ratiotemp), "method", "mlp");
  gst_object_unref(ratiotemp);
  tags = push_frame();
  ASSERT_EQ(tags.size(), 1u);
  const std::string changed = text(tags[0], GST_TAG_COMMENT);
  EXPECT_NE(changed.find("; method=mlp;"), std::string::npos) << changed;
  EXPECT_NE(changed.find("; e-slope=-12.5 %/100 nm"), std::string::npos) << changed;
  EXPECT_NE(changed.find("; misfit-probability=1e-06;"), std::string::npos) << changed;
  // These planes are not the fused path: the brightness readings are not made, nor said.
  EXPECT_NE(changed.find("; brightness-radius=0;"), std::string::npos) << changed;
  unref_all(tags);
}

TEST_F(RatioTempTags, uncertainty_output_says_so_and_no_exposure_when_unknown) {
  start("ratiotemp output=uncertainty model=" + rgb_model_path(), kCaps);
  auto tags = push_frame();
  ASSERT_EQ(tags.size(), 1u);
  const std::string comment = text(tags[0], GST_TAG_COMMENT);
  EXPECT_NE(comment.find("quantity=expanded-uncertainty;"), std::string::npos) << comment;
  EXPECT_EQ(comment.find("exposure"), std::string::npos) << comment;
  EXPECT_NE(text(tags[0], GST_TAG_TITLE).find("uncertainty"), std::string::npos);
  unref_all(tags);
}

// How demosaic25 made the planes changes the readings, so a recording says it where the caps
// do (a raw recording is then measured again with it).
TEST_F(RatioTempTags, the_demosaicking_the_caps_name_is_in_the_comment) {
  start("ratiotemp model=" + rgb_model_path(),
        std::string(kCaps) + ",demosaic=bilinear,pattern=rggb");
  auto tags = push_frame();
  ASSERT_EQ(tags.size(), 1u);
  const std::string comment = text(tags[0], GST_TAG_COMMENT);
  EXPECT_NE(comment.find("; brightness-radius=0; demosaic=bilinear"), std::string::npos) << comment;
  unref_all(tags);
}

// blur-correction and brightness-radius need the fused path: on plain planes they are not
// applied (a warning says so), and the comment said they were, so that measure --recording read
// the frames otherwise than ratiotemp had.
TEST_F(RatioTempTags, corrections_not_applied_are_not_in_the_comment) {
  start("ratiotemp blur-correction=true brightness-radius=2 model=" + rgb_model_path(),
        std::string(kCaps) + ",demosaic=bilinear,pattern=rggb");
  auto tags = push_frame();
  ASSERT_EQ(tags.size(), 1u);
  const std::string comment = text(tags[0], GST_TAG_COMMENT);
  EXPECT_NE(comment.find("; blur-correction=off; brightness-radius=0; demosaic=bilinear"),
            std::string::npos)
      << comment;
  unref_all(tags);
}

}  // namespace
}  // namespace pyrocam::test
