// The renderer's header and library resolve from the installed package (mjtether::render).
#include <mjtether/render.h>

#include <cstdio>

int main() {
  // NiceCeil is the colour scale's rounding: 130 N rounds up to 200 N (render.h).
  const double top = mjtether::render::NiceCeil(130);
  std::printf("NiceCeil(130) = %g\n", top);
  return top == 200 ? 0 : 1;
}
