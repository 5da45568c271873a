// render — the CMAM's state on the tracer's side: the caches of one strip of the image, one per
// (textured object, texture, ray path), and what a CMAM lookup records for the footprint AOV.
// The CMAM itself (texture/cmam.h) sits beside the filters; these are what the tracer keeps for
// it (algorithms.md §6.3).
#pragma once

#include <cmam/texture/cmam.h>

#include <cstdint>
#include <vector>

namespace cmam::render {

/// What the CMAM lookup of one texture node filtered (the footprint AOV): filled by that lookup
/// when a TexContext points here.
struct CmamRecord {
    int node = -1;  // the texture node to record
    bool filled = false;
    texture::CmamRegion region;
    texture::LookupInfo info;
};

/// The CMAM caches of one strip of the image: one per (textured object, texture, ray path).
/// A strip is traced top to bottom, each row left to right (with scanline tags, one row of
/// sample strata at a time), so samples reach the caches in scan order. The path (which
/// specular bounces led to the hit) keeps neighbours of different paths apart: a glass's
/// reflected and refracted rays, both at level 1, or a row that crosses from a direct view of an
/// object to its mirror image, would otherwise break each other's neighbourhoods.
class CmamRowState {
  public:
    texture::CmamCache& cache(uint32_t object, uint32_t texture_node, uint64_t path) {
        const uint64_t key = (uint64_t(object) << 32) | texture_node;
        if (m_last < m_caches.size() && m_caches[m_last].key == key &&
            m_caches[m_last].path == path)
            return m_caches[m_last].cache;  // a row mostly stays on one object
        return find_or_add(key, path);
    }
    void clear() {
        m_caches.clear();
        m_last = 0;
    }

  private:
    // The search past the last entry found, out of line so that the test above stays inline
    // wherever a texture asks for its cache.
    [[gnu::noinline]] texture::CmamCache& find_or_add(uint64_t key, uint64_t path) {
        for (std::size_t i = 0; i < m_caches.size(); ++i)
            if (m_caches[i].key == key && m_caches[i].path == path) {
                m_last = i;
                return m_caches[i].cache;
            }
        m_last = m_caches.size();
        return m_caches.push_back({key, path, texture::CmamCache{}}), m_caches.back().cache;
    }
    struct Entry {
        uint64_t key, path;
        texture::CmamCache cache;
    };
    std::vector<Entry> m_caches;
    std::size_t m_last = 0;  // the entry found last
};

}  // namespace cmam::render
