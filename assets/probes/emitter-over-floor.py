# Writes emitter-over-floor.gltf: a 4 m white floor (albedo 0.8, Lambertian) open to a black sky, a
# 2 cm square emitter of strength 1e4 1 m above its middle facing down, a camera 3 m up looking
# down. Usage: python3 emitter-over-floor.py emitter-over-floor.gltf [height]
import base64, json, struct, sys

import numpy as np


def scene(path, s=0.02, h=1.0, strength=1e4, half=2.0):
    quads = []  # (verts, normal, material)
    quads.append(([[-half,0,-half],[-half,0,half],[half,0,half],[half,0,-half]],[0,1,0],0))
    e=s/2
    quads.append(([[-e,h,-e],[e,h,-e],[e,h,e],[-e,h,e]],[0,-1,0],1))
    prims=[]; bufviews=[]; acc=[]
    data=b''
    for qi,(v,n,m) in enumerate(quads):
        p=b''.join(struct.pack('<3f',*x) for x in v); nn=b''.join(struct.pack('<3f',*n) for _ in v)
        # Wind each quad's triangles to face along its normal.
        a,b,c=[np.array(x) for x in v[:3]]
        tri=[0,1,2,0,2,3] if np.dot(np.cross(b-a,c-a),n)>0 else [0,2,1,0,3,2]
        ii=struct.pack('<6H',*tri)+b'\0\0'
        for blob,tgt in ((p,34962),(nn,34962),(ii,34963)):
            bufviews.append({"buffer":0,"byteOffset":len(data),"byteLength":len(blob),"target":tgt}); data+=blob
        bv=len(bufviews)
        mn=[min(x[k] for x in v) for k in range(3)]; mx=[max(x[k] for x in v) for k in range(3)]
        acc.append({"bufferView":bv-3,"componentType":5126,"count":4,"type":"VEC3","min":mn,"max":mx})
        acc.append({"bufferView":bv-2,"componentType":5126,"count":4,"type":"VEC3"})
        acc.append({"bufferView":bv-1,"componentType":5123,"count":6,"type":"SCALAR"})
        prims.append({"attributes":{"POSITION":len(acc)-3,"NORMAL":len(acc)-2},"indices":len(acc)-1,"material":m})
    spec={"KHR_materials_specular":{"specularFactor":0.0}}
    mats=[{"name":"floor","pbrMetallicRoughness":{"baseColorFactor":[0.8,0.8,0.8,1],"metallicFactor":0,"roughnessFactor":1},"extensions":spec},
          {"name":"emitter","pbrMetallicRoughness":{"baseColorFactor":[0.8,0.8,0.8,1],"metallicFactor":0,"roughnessFactor":1},"emissiveFactor":[1,1,1],
           "extensions":{"KHR_materials_emissive_strength":{"emissiveStrength":strength},**spec}}]
    g={"asset":{"version":"2.0"},"extensionsUsed":["KHR_materials_emissive_strength","KHR_materials_specular"],
       "scene":0,"scenes":[{"nodes":[0,1]}],
       "nodes":[{"mesh":0},{"camera":0,"translation":[0,3,0],"rotation":[-0.70710678,0,0,0.70710678]}],
       "cameras":[{"type":"perspective","perspective":{"yfov":1.22,"znear":0.05,"aspectRatio":1.0}}],
       "meshes":[{"primitives":prims}],"materials":mats,
       "buffers":[{"byteLength":len(data),"uri":"data:application/octet-stream;base64,"+base64.b64encode(data).decode()}],
       "bufferViews":bufviews,"accessors":acc}
    json.dump(g, open(path, 'w'), indent=4)
scene(sys.argv[1], h=float(sys.argv[2]) if len(sys.argv)>2 else 1.0)
